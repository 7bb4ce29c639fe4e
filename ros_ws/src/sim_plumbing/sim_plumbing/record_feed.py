"""The recorder's feed: a node started by the scenario runner hands the serialized bytes of its
per-step outputs to the runner's recorder directly, besides publishing them.

Why: with every node in its own process, each recorded message cost a second DDS delivery
(shared-memory push, a wake-up of the runner) for about 12 messages a step: a quarter of the
CPU of a recorded run. The bytes a node publishes are the ones it writes here (the per-step
messages are CDR it wrote itself, sim_plumbing/cdr.py), so the recording is unchanged; topics
from anybody else (commands, events, outside autopilots) are still recorded by subscription.

A node finds its feed in the environment: TUGSIM_RECORD_FD names the write end of a pipe the
runner passed it; or, with every node in the runner's process, the runner installs a
function. Without either (a node started by hand) nothing is fed.

Pipe frames, little endian: kind (uint8: 0 names a topic, 1 is a message), topic id (uint16),
log time (int64 ns; 0 for kind 0), length (uint32), then that many bytes (the topic name, or
the serialized message). One writer per pipe, so frames never interleave.
"""
from __future__ import annotations

import os
import struct
from typing import Callable, Dict, Iterator, List, Optional, Tuple

from sim_plumbing import local_bus

ENV_FD = "TUGSIM_RECORD_FD"
_FRAME = struct.Struct("<BHqI")
_NAME, _MESSAGE = 0, 1

FeedFunction = Callable[[str, int, bytes], None]  # (topic, log time ns, serialized message)


class PipeFeed:
    """Writer side: frames into the pipe the runner reads."""

    def __init__(self, fd: int):
        self.fd = fd
        self.ids: Dict[str, int] = {}

    def _write_all(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            view = view[os.write(self.fd, view):]

    def __call__(self, topic: str, log_time_ns: int, data: bytes) -> None:
        topic_id = self.ids.get(topic)
        if topic_id is None:
            topic_id = self.ids[topic] = len(self.ids)
            name = topic.encode()
            self._write_all(_FRAME.pack(_NAME, topic_id, 0, len(name)) + name)
        self._write_all(_FRAME.pack(_MESSAGE, topic_id, log_time_ns, len(data)) + data)


class PipeReader:
    """Reader side (the recorder): non-blocking, whatever whole frames have arrived."""

    def __init__(self, fd: int):
        os.set_blocking(fd, False)
        self.fd = fd
        self.names: Dict[int, str] = {}
        self._buf = bytearray()
        self.closed = False

    def read(self) -> Iterator[Tuple[str, int, bytes]]:
        """(topic, log time ns, message) of every complete message frame now in the pipe."""
        while not self.closed:
            try:
                chunk = os.read(self.fd, 1 << 20)
            except BlockingIOError:
                break
            if not chunk:
                self.closed = True  # the node exited; a torn last frame is dropped
                break
            self._buf += chunk
        buf, pos = self._buf, 0
        while len(buf) - pos >= _FRAME.size:
            kind, topic_id, log_time, n = _FRAME.unpack_from(buf, pos)
            end = pos + _FRAME.size + n
            if end > len(buf):
                break
            payload = bytes(buf[pos + _FRAME.size:end])
            pos = end
            if kind == _NAME:
                self.names[topic_id] = payload.decode()
            else:
                yield self.names[topic_id], log_time, payload
        del buf[:pos]

    def close(self) -> None:
        if self.fd >= 0:
            os.close(self.fd)
            self.fd = -1


_installed: List[Optional[FeedFunction]] = [None]


def install(feed: Optional[FeedFunction]) -> None:
    """Nodes constructed from now on in this process feed this function (None: stop)."""
    _installed[0] = feed


def current() -> Optional[FeedFunction]:
    """The feed of a node constructed now: installed in-process, from the environment, or None."""
    if _installed[0] is not None:
        return _installed[0]
    fd = os.environ.get(ENV_FD)
    if fd:
        _installed[0] = PipeFeed(int(fd))
    return _installed[0]


class FedPublisher:
    """A publisher of serialized messages that also feeds them to the recorder."""

    def __init__(self, publisher, feed: Optional[FeedFunction]):
        self.publisher = publisher
        self.topic = publisher.topic_name
        self.feed = feed

    def publish(self, data: bytes, log_time_ns: int) -> None:
        self.publisher.publish(data)
        local_bus.post(self.topic, data)  # to this process's nodes that take the topic locally
        if self.feed is not None:
            self.feed(self.topic, log_time_ns, data)
