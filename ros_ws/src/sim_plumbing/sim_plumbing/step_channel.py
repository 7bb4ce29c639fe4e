"""The runner's private channel to each node it starts: the step protocol's triggers go out and
the nodes' answers come back on it, and only there are they trusted.

Why: anybody on the DDS domain reads /sim/step and /sim/step_done (the run id, the node names)
and can publish on them, and this Fast DDS has no DDS Security (docs/step-protocol.md, threat
model). A stranger answering StepDone(k+1) "ok" for every node made a run end "3000 steps, exit
0" while the nodes had stopped at step 107; a forged ok=false stopped it with the stranger's text.
A channel the runner made itself and handed only to the process it started is not on the wire:
what comes out of it is the node's own word. /sim/step and /sim/step_done are still published
(observers, the recording); the runner and its nodes no longer act on them for each other.

Channels:
- a node process: one end of an AF_UNIX SOCK_SEQPACKET socketpair (message boundaries kept, so
  one send is one frame), inherited through pass_fds, its descriptor named by TUGSIM_STEP_CHANNEL_FD;
- a node group process (several nodes on one executor, scenario_runner.node_group): one
  socketpair per node, the descriptors named by TUGSIM_STEP_CHANNEL_FDS (JSON, by node name);
- a node in the runner's process (--layout one_process, or the runner's own group): a pair of
  in-memory queues, found by the node's name through install();
- a node somebody else started (--external, other PCs): none; it steps on the DDS messages of the
  run (run id, step), with the trust docs/step-protocol.md states.

Frames (little endian):
  runner -> node: b"T", step (uint64), then the namespaces SimStep.ordered names, "\\n"-joined
  node -> runner: b"D", step (uint64), compute time (float64), ok (uint8), refused messages
      (uint32), then the error text (UTF-8; empty when ok)
"""
from __future__ import annotations

import collections
import os
import socket
import struct
from typing import Callable, Deque, Dict, List, NamedTuple, Optional, Tuple

ENV_FD = "TUGSIM_STEP_CHANNEL_FD"
ENV_FDS = "TUGSIM_STEP_CHANNEL_FDS"  # a node group process: {"/tug/vessel": fd, ...} as JSON
_TRIGGER = struct.Struct("<cQ")
_DONE = struct.Struct("<cQd?I")
MAX_FRAME = 1 << 16  # an error text longer than this is cut (a frame is one datagram)


class Trigger(NamedTuple):
    step: int
    ordered: Tuple[str, ...]


class Answer(NamedTuple):
    step: int
    compute_time: float
    ok: bool
    refused: int
    error: str


class ChannelBroken(RuntimeError):
    """The other end is gone or sent something that is not a frame of this protocol."""


def _encode_trigger(step: int, ordered) -> bytes:
    return _TRIGGER.pack(b"T", step) + "\n".join(ordered).encode()


def _decode_trigger(frame: bytes) -> Trigger:
    if len(frame) < _TRIGGER.size or frame[:1] != b"T":
        raise ChannelBroken(f"not a trigger frame ({len(frame)} bytes)")
    _, step = _TRIGGER.unpack_from(frame)
    text = frame[_TRIGGER.size:].decode()
    return Trigger(step, tuple(text.split("\n")) if text else ())


def _encode_answer(a: Answer) -> bytes:
    error = a.error.encode()[:MAX_FRAME - _DONE.size]
    return _DONE.pack(b"D", a.step, a.compute_time, a.ok, a.refused) + error


def _decode_answer(frame: bytes) -> Answer:
    if len(frame) < _DONE.size or frame[:1] != b"D":
        raise ChannelBroken(f"not an answer frame ({len(frame)} bytes)")
    _, step, compute_time, ok, refused = _DONE.unpack_from(frame)
    return Answer(step, compute_time, ok, refused, frame[_DONE.size:].decode(errors="replace"))


class _SocketEnd:
    """One end of the socketpair: sends whole frames (blocking: a frame is small and the other
    side drains every step), receives what has arrived without waiting."""

    def __init__(self, sock: socket.socket):
        self.sock = sock
        self.closed = False

    def _send(self, frame: bytes) -> None:
        try:
            self.sock.sendall(frame)
        except (BrokenPipeError, ConnectionResetError) as exc:
            raise ChannelBroken(f"the other end is gone ({exc})") from exc

    def _frames(self) -> List[bytes]:
        out = []
        while not self.closed:
            try:
                frame = self.sock.recv(MAX_FRAME, socket.MSG_DONTWAIT)
            except BlockingIOError:
                break
            except (ConnectionResetError, OSError):
                self.closed = True
                break
            if not frame:
                self.closed = True  # the other end exited
                break
            out.append(frame)
        return out

    def fileno(self) -> int:
        return self.sock.fileno()

    def close(self) -> None:
        self.sock.close()
        self.closed = True


class NodeEnd(_SocketEnd):
    """What a node holds: triggers in, answers out."""

    def send_answer(self, answer: Answer) -> None:
        self._send(_encode_answer(answer))

    def triggers(self) -> List[Trigger]:
        return [_decode_trigger(f) for f in self._frames()]


class RunnerEnd(_SocketEnd):
    """What the runner holds for one node process: triggers out, answers in."""

    def send_trigger(self, step: int, ordered) -> None:
        self._send(_encode_trigger(step, ordered))

    def answers(self) -> List[Answer]:
        return [_decode_answer(f) for f in self._frames()]


def socket_pair() -> Tuple[RunnerEnd, int]:
    """(the runner's end, the node's descriptor to pass with pass_fds; close it after the start)."""
    mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    theirs.set_inheritable(True)
    return RunnerEnd(mine), theirs.detach()


class _LocalEnd:
    """One end of an in-process channel (--layout one_process): two queues, no descriptor."""

    def __init__(self, inbox: Deque, outbox: Deque):
        self._in, self._out = inbox, outbox
        self.closed = False

    def _take(self) -> list:
        out = list(self._in)
        self._in.clear()
        return out

    def close(self) -> None:
        self.closed = True


class LocalNodeEnd(_LocalEnd):
    def send_answer(self, answer: Answer) -> None:
        self._out.append(answer)

    def triggers(self) -> List[Trigger]:
        return self._take()


class LocalRunnerEnd(_LocalEnd):
    def send_trigger(self, step: int, ordered) -> None:
        self._out.append(Trigger(step, tuple(ordered)))

    def answers(self) -> List[Answer]:
        return self._take()


def local_pair() -> Tuple[LocalRunnerEnd, LocalNodeEnd]:
    to_node: Deque = collections.deque()
    to_runner: Deque = collections.deque()
    return LocalRunnerEnd(to_runner, to_node), LocalNodeEnd(to_node, to_runner)


_installed: List[Optional[Callable[[str], Optional[LocalNodeEnd]]]] = [None]


def install(lookup: Optional[Callable[[str], Optional[LocalNodeEnd]]]) -> None:
    """Nodes constructed from now on in this process find their channel by their name here
    (None: stop)."""
    _installed[0] = lookup


def for_node(name: str):
    """The channel of the node named `name` ("/tug/vessel"): installed in-process, inherited from
    the runner (TUGSIM_STEP_CHANNEL_FD, taken once: a second node of the process gets none), or
    None (started by somebody else)."""
    if _installed[0] is not None:
        return _installed[0](name)
    fd = os.environ.pop(ENV_FD, None)
    if not fd:
        return None
    return NodeEnd(socket.socket(fileno=int(fd)))


def group_channels() -> Dict[str, NodeEnd]:
    """A node group process's channels by node name (TUGSIM_STEP_CHANNEL_FDS, taken once)."""
    import json
    text = os.environ.pop(ENV_FDS, None)
    if not text:
        return {}
    return {name: NodeEnd(socket.socket(fileno=int(fd))) for name, fd in json.loads(text).items()}
