"""Per-step state messages handed from node to node inside one process, without DDS.

Why: when the nodes of a run share a process (`--layout one_process`, a node group, the
runner's own group), every message between them still went through Fast DDS and the rclpy
executor: the writer delivers to an in-process reader inside its publish call, then the
executor wakes, takes and dispatches it. Measured for hull interaction (issue 33): about 60 us
a message, twelve messages a step for six vessels, most of what the interaction node added to a
step. rclcpp has intra-process communication for this; rclpy has none.

How:
- a `FedPublisher` (record_feed) posts the bytes it publishes here as well; they still go out on
  DDS for everybody else (observers, the live view, a user's autopilot) and to the recorder;
- a `SteppedNode` input declared `local=True` registers a handler for its topic. The bytes are
  the publisher's own CDR, so the node takes them exactly as it takes the wire's copy;
- the first local delivery on a topic switches that input off DDS: its subscription is
  destroyed, so the writer no longer delivers to an in-process reader and the executor no
  longer wakes for it. Until then both copies come; they are the same bytes, and the stepping
  machinery keeps one (an identical copy for a step changes nothing);
- deliveries posted while a node computes and publishes a step wait until that node's step is
  over (`stepping()`), then go out in the order posted: a receiving node never computes inside
  another node's publish, and each node's compute time stays its own.

Trust: what comes through here is the output of a node in this process, started by the run. A
message somebody else publishes on a topic taken locally is not read at all (it can change
nothing; it is not counted either, since it is never received). Everything here runs on the
process's one executor thread (ros_common.make_executor: single-threaded).
"""
from __future__ import annotations

import collections
import contextlib
from typing import Callable, Deque, Dict, List, Tuple

Handler = Callable[[bytes], None]

_handlers: Dict[str, List[Handler]] = {}
_pending: Deque[Tuple[List[Handler], bytes]] = collections.deque()
_depth = [0]          # nodes inside a step (nested when a delivery lets another node step)
_flushing = [False]


def subscribe(topic: str, handler: Handler) -> Callable[[], None]:
    """Deliver the bytes every in-process publisher of `topic` (fully qualified) posts from now
    on; returns the function that ends it."""
    _handlers.setdefault(topic, []).append(handler)

    def unsubscribe() -> None:
        handlers = _handlers.get(topic, [])
        if handler in handlers:
            handlers.remove(handler)
        if not handlers:
            _handlers.pop(topic, None)
    return unsubscribe


def has_subscribers(topic: str) -> bool:
    return bool(_handlers.get(topic))


def post(topic: str, data: bytes) -> None:
    """A publisher's bytes for the in-process handlers of `topic` (none: nothing to do)."""
    handlers = _handlers.get(topic)
    if not handlers:
        return
    _pending.append((list(handlers), data))
    if _depth[0] == 0:
        flush()


def flush() -> None:
    """Deliver what was posted, in order, including what the deliveries themselves post."""
    if _flushing[0]:
        return  # the outer flush takes it
    _flushing[0] = True
    try:
        while _pending:
            handlers, data = _pending.popleft()
            for handler in handlers:
                handler(data)
    finally:
        _flushing[0] = False


@contextlib.contextmanager
def stepping():
    """Around a node's compute-publish-answer: its posts are delivered when it is over."""
    _depth[0] += 1
    try:
        yield
    finally:
        _depth[0] -= 1
    if _depth[0] == 0:
        flush()


def reset() -> None:
    """Forget every handler and pending delivery (a process that ends its nodes; tests)."""
    _handlers.clear()
    _pending.clear()
    _depth[0] = 0
    _flushing[0] = False
