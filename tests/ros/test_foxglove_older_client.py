"""A Foxglove client of the older vintage against the live view of a paced run: the npm package
@foxglove/ws-protocol 0.8.0 (the protocol library of Lichtblick releases before December 2025),
which offers only the subprotocol `foxglove.websocket.v1`, where the foxglove-sdk server speaks
`foxglove.sdk.v1` (the same protocol renamed; live_view/front.py negotiates):

- the client (tests/ros/foxglove_older_client.js under Node.js, the packages pinned in the live
  view's web/package-lock.json) connects, is answered with the subprotocol it offered, sees the
  channel /tug/odom (CDR, ros2msg nav_msgs/msg/Odometry), subscribes and decodes three messages
  (from 5 s of simulation time on) with @foxglove/cdr's reader, every byte of each consumed;
- each decoded pose and twist equals, to the bit, the recorded /tug/odom message of its stamp
  (read back from the run's MCAP with mcap-ros2-support);
- a WebSocket upgrade offering neither name is refused with 400 and a text naming both.
"""
import json
import os
import shutil
import socket
import subprocess
import time

import pytest
import yaml

from conftest import executable_path, free_port
from test_recording import decoded

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]

HERE = os.path.dirname(os.path.abspath(__file__))
WEB_MODULES = os.path.join(HERE, "..", "..", "ros_ws", "src", "live_view", "web", "node_modules")
DURATION = 20.0
COUNT = 3
AFTER_S = 5  # s of simulation time: the tug under way


def _free_port() -> int:
    return free_port()


def _wait_listening(port: int, proc, timeout: float) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            return
        except OSError:
            time.sleep(0.2)
    pytest.fail(f"the live view did not listen on {port} within {timeout:g} s")


def _handshake(port: int, protocols: str) -> str:
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall((f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                   "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
                   f"Sec-WebSocket-Protocol: {protocols}\r\n\r\n").encode())
        answer = b""
        while True:
            chunk = s.recv(4096)
            if not chunk:
                return answer.decode("latin-1")
            answer += chunk


def test_an_older_foxglove_client_subscribes_and_decodes_odometry(tmp_path, ros_domain):
    node = shutil.which("node")
    assert node, "Node.js is needed (Debian: apt-get install nodejs npm), then source scripts/ensure_env.sh"
    assert os.path.isdir(os.path.join(WEB_MODULES, "@foxglove", "ws-protocol")), \
        "the live view's npm packages are missing: source scripts/ensure_env.sh (npm ci in ros_ws/src/live_view/web)"
    from ament_index_python.packages import get_package_share_directory
    share = get_package_share_directory("scenario_runner")
    sc = dict(yaml.safe_load(open(f"{share}/scenarios/default_demo.yaml")), name="older", mode="realtime",
              duration=DURATION)
    sc["events"] = [{"time": 0.0, "vessel": "tug", "engine_order": 0.6}]  # under way: no zeros to compare
    path = tmp_path / "older.yaml"
    path.write_text(yaml.safe_dump(sc))
    out = tmp_path / "older.mcap"
    port = _free_port()
    run = subprocess.Popen([executable_path("scenario_runner", "run_scenario"), str(path), "--output", str(out),
                            "--quiet", "--live", "--live-port", str(port)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_listening(port, run, 120.0)
        refused = _handshake(port, "some.other.protocol")
        client = subprocess.run([node, os.path.join(HERE, "foxglove_older_client.js"), f"ws://127.0.0.1:{port}",
                                 "/tug/odom", str(COUNT), str(AFTER_S)], capture_output=True, text=True, timeout=90,
                                env=dict(os.environ, NODE_PATH=os.path.abspath(WEB_MODULES)))
        stdout, stderr = run.communicate(timeout=200)
    finally:
        if run.poll() is None:
            run.kill()
            run.communicate()
    assert run.returncode == 0, stdout + stderr
    assert refused.startswith("HTTP/1.1 400 "), refused
    assert "foxglove.sdk.v1" in refused and "foxglove.websocket.v1" in refused, refused
    assert client.returncode == 0, client.stdout + client.stderr
    got = json.loads(client.stdout.strip().splitlines()[-1])
    assert got["offered"] == "foxglove.websocket.v1" and got["protocol"] == "foxglove.websocket.v1", got
    assert got["channel"] == {"topic": "/tug/odom", "encoding": "cdr", "schemaName": "nav_msgs/msg/Odometry",
                              "schemaEncoding": "ros2msg"}, got["channel"]
    assert len(got["messages"]) == COUNT
    odom = decoded(out, ["/tug/odom"])["/tug/odom"]
    recorded = {m.header.stamp.sec * 10**9 + m.header.stamp.nanosec: m for m in odom}
    for m in got["messages"]:
        assert m["consumed"] == m["length"], m  # the whole message is an Odometry, field for field
        stamp = m["stamp"]["sec"] * 10**9 + m["stamp"]["nanosec"]
        truth = recorded[stamp]
        p, q, tw = truth.pose.pose.position, truth.pose.pose.orientation, truth.twist.twist
        assert m["frame_id"] == truth.header.frame_id and m["child_frame_id"] == truth.child_frame_id
        assert m["position"] == [p.x, p.y, p.z], (m, truth)
        assert m["orientation"] == [q.x, q.y, q.z, q.w], (m, truth)
        assert m["linear"] == [tw.linear.x, tw.linear.y, tw.linear.z]
        assert m["angular"] == [tw.angular.x, tw.angular.y, tw.angular.z]
    # the tug was moving: the comparison was not of zeros
    assert all(m["stamp"]["sec"] >= AFTER_S and abs(m["linear"][0]) > 0.1 for m in got["messages"]), got["messages"]


def test_subprotocol_negotiation_in_process():
    """The front door's choice (live_view.front): the SDK's name when offered, else the older
    name of the same protocol, else a refusal naming both; the header rewritten in a head, the
    other lines byte for byte."""
    from live_view.front import negotiate_subprotocol, offered_subprotocols, with_subprotocol
    assert negotiate_subprotocol(["foxglove.websocket.v1", "foxglove.sdk.v1"]) == ("foxglove.sdk.v1", None)
    assert negotiate_subprotocol(["foxglove.websocket.v1"]) == ("foxglove.websocket.v1", None)
    for offered in ([], ["some.other.protocol"], ["foxglove.websocket.v2"]):
        chosen, why = negotiate_subprotocol(offered)
        assert chosen is None and "foxglove.sdk.v1 or foxglove.websocket.v1" in why, why
    assert offered_subprotocols({"sec-websocket-protocol": " a , foxglove.websocket.v1,,"}) == \
        ["a", "foxglove.websocket.v1"]
    head = (b"HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\n"
            b"Sec-WebSocket-Accept: s3pPLMBiTxaQ9kYGzzhZRbK+xOo=\r\nsec-websocket-protocol: foxglove.sdk.v1\r\n\r\n")
    assert with_subprotocol(head, "foxglove.websocket.v1") == head.replace(
        b"sec-websocket-protocol: foxglove.sdk.v1", b"sec-websocket-protocol: foxglove.websocket.v1")
