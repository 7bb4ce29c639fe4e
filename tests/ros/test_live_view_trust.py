"""Who may talk to the live view, and how much: the pure checks of live_view.trust and
live_view.client_input, in-process (no node). The same checks through a real node, on both
surfaces (WebSocket and the instructor station's HTTP), are in test_live_view_web.py.

- Host: exactly a loopback name with the served port; DNS-rebinding names that merely start or
  end like one (127.attacker.example, 127.0.0.1.nip.io) are refused;
- Origin: a page of another site (http://evil.example) is refused, this machine's own pages and
  the configured allowed_origins are not, a program (no Origin) is not;
- JSON bombs (a 400-digit number, 2000 nested brackets) are refused with a reason, not raised;
- the rate limit is one bucket per kind of client and order, whatever the connections;
- a /clock that jumps ahead is not followed.
"""
import pytest

from live_view import client_input
from live_view.trust import ClockGuard, SharedLimits, WebPolicy, parse_origins

pytestmark = pytest.mark.timeout(30)

WS, HTTP = 8765, 8080


@pytest.fixture
def policy():
    return WebPolicy("127.0.0.1", [WS, HTTP])


@pytest.mark.parametrize("host", ["127.attacker.example", "127.0.0.1.nip.io", "localhost.attacker.example",
                                  "attacker.example", "127.0.0.1.", "localhost.", "127.1", "0.0.0.0",
                                  "127.0.0.1@attacker.example", "localhost, 127.0.0.1"])
def test_dns_rebinding_hosts_refused(policy, host):
    why = policy.host_refusal(f"{host}:{WS}", WS)
    assert why is not None and "Host header" in why, why


def test_loopback_hosts_with_the_served_port(policy):
    for host in ("localhost", "127.0.0.1", "[::1]", "LOCALHOST"):
        assert policy.host_refusal(f"{host}:{WS}", WS) is None, host
        why = policy.host_refusal(f"{host}:{HTTP}", WS)  # another port than this server's
        assert why is not None and f"port {HTTP}" in why, why
    assert "no Host header" in policy.host_refusal(None, WS)
    assert policy.host_refusal("localhost", 80) is None  # no port: 80
    assert policy.host_refusal("localhost", WS) is not None


def test_host_of_a_server_on_another_address():
    lan = WebPolicy("0.0.0.0", [WS], parse_origins("http://sim-pc.local:8080"))
    assert lan.host_refusal(f"192.168.1.5:{WS}", WS) is None  # an address cannot be rebound
    assert lan.host_refusal(f"sim-pc.local:{WS}", WS) is None  # named by allowed_origins
    assert lan.host_refusal(f"attacker.example:{WS}", WS) is not None


def test_browser_origin_refused(policy):
    for origin in ("http://evil.example", "https://evil.example", "null", "http://127.attacker.example:8765",
                   "http://localhost:9999", "file://", "http://localhost.evil.example:8765",
                   "http://127.0.0.1.nip.io:8765"):
        why = policy.origin_refusal(origin)
        assert why is not None and "is not allowed" in why and "allowed_origins" in why, (origin, why)


def test_own_pages_and_allowed_origins(policy):
    for origin in ("http://localhost:8765", "http://127.0.0.1:8080", "http://[::1]:8080", "http://LOCALHOST:8080/"):
        assert policy.origin_refusal(origin) is None, origin
    assert policy.origin_refusal(None) is None  # a program, not a page
    configured = WebPolicy("127.0.0.1", [WS], parse_origins("https://app.foxglove.dev, https://lichtblick.example"))
    assert configured.origin_refusal("https://app.foxglove.dev") is None
    assert configured.origin_refusal("https://app.foxglove.dev.evil.example") is not None
    with pytest.raises(ValueError, match="not an origin"):
        parse_origins("app.foxglove.dev")
    with pytest.raises(ValueError, match="not an origin"):
        parse_origins("https://")
    desktop = WebPolicy("127.0.0.1", [WS], parse_origins("file://"))  # a desktop app's pages
    assert desktop.origin_refusal("file://") is None and desktop.origin_refusal("null") is not None


@pytest.mark.parametrize("body", [
    b'{"engine_order": 1' + b"0" * 399 + b"}",                   # a 400-digit number
    b'{"engine_order": ' + b"[" * 2000 + b"]" * 2000 + b"}",     # 2000 nested brackets
    b"[" * 2000 + b"]" * 2000,
    b'{"engine_order": 1e999999}',
    b'{"engine_order": 0.5, "header": {"stamp": {"sec": {"a": {"b": 1}}}}}',
])
def test_json_bombs_refused(body):
    assert len(body) <= client_input.MAX_MESSAGE_BYTES
    with pytest.raises(client_input.InputRefused):
        client_input.check(client_input.VESSEL_COMMAND, body, "json", 0)
    with pytest.raises(client_input.InputRefused):
        client_input.check(client_input.WINCH_COMMAND, body.replace(b"engine_order", b"payout_rate"), "json", 0)


def test_ordinary_json_still_taken():
    order = client_input.check(client_input.VESSEL_COMMAND,
                               b'{"engine_order": 0.5, "steering_angle": -0.1, "anchor": 0, '
                               b'"header": {"stamp": {"sec": 1, "nanosec": 0}, "frame_id": ""}}', "json", 7)
    assert order.notes == ()
    assert client_input.check(client_input.WINCH_COMMAND, b'{"payout_rate": 12.5}', "json", 0).notes


def test_shared_rate_whatever_the_clients():
    limits = SharedLimits(lambda: 20.0)
    taken = sum(limits.take("http", "VesselCommand", 100.0 + i * 1e-4) for i in range(800))  # 40 addresses x 20
    assert taken == 20 + int(20 * 0.08)  # the burst of one second and what 0.08 s refilled, shared
    assert limits.take("http", "WinchCommand", 100.1)  # another kind of order has its own
    assert limits.take("websocket", "VesselCommand", 100.1)  # and another kind of client
    assert limits.take("http", "VesselCommand", 100.2)  # refilled at 20/s


def test_clock_that_jumps_is_not_followed():
    guard = ClockGuard()
    assert guard.observe(10_000_000_000, 0.0) is None
    assert guard.observe(10_050_000_000, 0.05) is None
    why = guard.observe(2_000_000_000 * 1_000_000_000, 0.06)  # a stranger's 2e9 s
    assert why is not None and "jumped" in why and guard.time_ns == 10_050_000_000
    assert guard.observe(10_100_000_000, 0.1) is None
    assert guard.observe(0, 0.2) is None  # a new run or a replay from the start
    assert guard.observe(50_000_000_000, 0.3) is None  # a start at an offset


def test_a_vessel_on_a_prescribed_motion_offers_the_web_no_order_topic():
    """The live view serves order topics only of vessels that take orders: an order to a vessel
    on a prescribed motion is refused at the web edge, not answered "accepted" and then refused
    by the vessel (issue 30 item 3)."""
    import os
    from ament_index_python.packages import get_package_share_directory
    from scenario_format.scenario import load_scenario
    from scenario_runner.run_scenario import live_topics
    sc = load_scenario(os.path.join(get_package_share_directory("scenario_runner"), "scenarios",
                                    "seed000_sinusoidal_sway.yaml"))
    served = {t for t, _type, _latched in live_topics(sc)}
    moving = [v.name for v in sc.vessels if v.motion is not None]
    free = [v.name for v in sc.vessels if v.motion is None]
    assert moving
    for name in moving:
        assert f"/{name}/command" not in served and f"/{name}/odom" in served
    for name in free:
        assert f"/{name}/command" in served
