"""Who may talk to the live view, and how much (no ROS import: pure checks, tested in-process).

- host_refusal / origin_refusal: the checks of a request's ``Host`` and ``Origin`` headers, the
  same for the WebSocket upgrade (front.py) and the instructor station's HTTP (instructor.py).
  Host: exactly a loopback name (localhost, 127.0.0.1, [::1]) with the served port; a server
  bound to another address also answers to an IP address (an address cannot be rebound) and to
  the host names of ``allowed_origins``. A name merely starting or ending like one
  (127.attacker.example, 127.0.0.1.nip.io) is a DNS-rebinding page and is refused.
  Origin (sent by every browser on a WebSocket upgrade and on a POST): absent (a program, not a
  page) or exactly http://localhost|127.0.0.1|[::1] with one of this node's ports (its own
  page), the bind address with such a port, or one of ``allowed_origins``.
- SharedLimits: one token bucket per kind of client (WebSocket, HTTP) and kind of order (vessel
  command, winch), whatever the number of connections or addresses: 40 loopback addresses or
  ten connections get together what one gets.
- ClockGuard: the time a stand-alone live view stamps orders with, from a /clock it cannot
  authenticate: a message that jumps ahead of what the wall clock allows is not followed.
"""
from __future__ import annotations

import ipaddress
import threading
from typing import Dict, Iterable, Optional, Sequence, Tuple

LOOPBACK_HOSTS = ("localhost", "127.0.0.1", "[::1]")
WILDCARD_HOSTS = ("", "0.0.0.0", "::", "[::]")
MAX_HEADER_VALUE = 255  # characters of a Host or Origin header looked at (longer is refused)


def is_loopback_bind(host: str) -> bool:
    """The server listens on a loopback address only."""
    return host in ("localhost", "::1") or _ip(host) is not None and _ip(host).is_loopback


def _ip(name: str):
    """The IP address a host name is written as (v6 in brackets or not), else None."""
    try:
        return ipaddress.ip_address(name[1:-1] if name.startswith("[") and name.endswith("]") else name)
    except ValueError:
        return None


def split_host(value: str, default_port: int) -> Optional[Tuple[str, int]]:
    """(name, port) of a Host header value or of an origin's authority ('[::1]:8080',
    'localhost'), the name lower case; None when it is not of that form."""
    value = value.strip().lower()
    if value.startswith("["):
        end = value.find("]")
        if end < 0:
            return None
        name, rest = value[:end + 1], value[end + 1:]
    else:
        name, _, port_text = value.partition(":")
        rest = ":" + port_text if _ else ""
    if rest:
        if not rest.startswith(":") or not rest[1:].isdigit() or len(rest) > 6:
            return None
        port = int(rest[1:])
    else:
        port = default_port
    if not name or any(c in name for c in "/@?#\\ \t"):
        return None
    return name, port


def _shown(value: Optional[str]) -> str:
    return repr(value[:100]) if value is not None else "none"


class WebPolicy:
    """The Host and Origin checks of one server (see the module docstring). ports: this node's
    served ports (its own pages are on them); bind_host: the address it listens on;
    allowed_origins: further origins allowed (e.g. https://app.foxglove.dev), exact."""

    def __init__(self, bind_host: str, ports: Iterable[int], allowed_origins: Sequence[str] = ()):
        self.bind_host = bind_host.strip().lower()
        self.loopback = is_loopback_bind(self.bind_host)
        self.ports = tuple(sorted({int(p) for p in ports if p}))
        self.allowed_origins = tuple(sorted({normalise_origin(o) for o in allowed_origins if o.strip()}))
        self.allowed_names = {split_host(o.partition("://")[2], 0)[0] for o in self.allowed_origins
                              if o.startswith(("http://", "https://")) and split_host(o.partition("://")[2], 0)}

    def host_refusal(self, host: Optional[str], served_port: int) -> Optional[str]:
        """None if a request to served_port with this Host header is for this server, else why not."""
        if host is None or not host.strip():
            return "no Host header"
        parsed = split_host(host, 80) if len(host) <= MAX_HEADER_VALUE else None
        if parsed is None:
            return f"Host header {_shown(host)} is not a host name with an optional port"
        name, port = parsed
        if port != served_port:
            return f"Host header {_shown(host)} names port {port}, this server is on port {served_port}"
        if name in LOOPBACK_HOSTS or name == "::1":
            return None
        if not self.loopback and (_ip(name) is not None or name in self.allowed_names):
            return None
        expected = ", ".join(f"{n}:{served_port}" for n in LOOPBACK_HOSTS)
        return (f"Host header {_shown(host)} is not this machine (expected exactly one of {expected}"
                f"{'' if self.loopback else ', an IP address or a host of allowed_origins'}): "
                "a page of another site reaching this port by its own name (DNS rebinding)")

    def origin_refusal(self, origin: Optional[str]) -> Optional[str]:
        """None if a request with this Origin header (None: absent, not a browser page) may go on."""
        if origin is None:
            return None
        if len(origin) > MAX_HEADER_VALUE:
            return f"Origin header of {len(origin)} characters"
        value = normalise_origin(origin)
        if value in self.allowed_origins:
            return None
        scheme, sep, authority = value.partition("://")
        parsed = split_host(authority, {"http": 80, "https": 443}.get(scheme, 0)) if sep else None
        if scheme in ("http", "https") and parsed is not None:
            name, port = parsed
            own_names = LOOPBACK_HOSTS if self.loopback or self.bind_host in WILDCARD_HOSTS else \
                LOOPBACK_HOSTS + (self._bracketed(self.bind_host),)
            if name in own_names and port in self.ports:
                return None
        pages = ", ".join(f"http://{n}:{p}" for p in self.ports for n in LOOPBACK_HOSTS)
        return (f"Origin {_shown(origin)} is not allowed: a page of another site may not use this server "
                f"(allowed: this machine's own pages, {pages}; and parameter allowed_origins: "
                f"{', '.join(self.allowed_origins) or 'none'})")

    @staticmethod
    def _bracketed(host: str) -> str:
        ip = _ip(host)
        return f"[{ip}]" if ip is not None and ip.version == 6 else host


def normalise_origin(origin: str) -> str:
    """An origin as compared: lower case, without a trailing slash after a host."""
    value = origin.strip().lower()
    return value[:-1] if value.endswith("/") and not value.endswith("://") else value


def parse_origins(text: str) -> Tuple[str, ...]:
    """The origins of parameter allowed_origins (comma or space separated), compared exactly: a
    web page's http(s)://host[:port], or what a desktop app's pages send (file://, an app's own
    scheme://...: no web site can send those); ValueError for anything else."""
    out = []
    for item in text.replace(",", " ").split():
        scheme, sep, authority = normalise_origin(item).partition("://")
        web = scheme in ("http", "https")
        if not sep or not scheme.isascii() or not (scheme[:1].isalpha() and all(
                c.isalnum() or c in "+-." for c in scheme)) or (web and split_host(authority, 0) is None):
            raise ValueError(f"allowed_origins: {item!r} is not an origin (scheme://host[:port], e.g. "
                             "https://app.foxglove.dev)")
        out.append(normalise_origin(item))
    return tuple(out)


class TokenBucket:
    """At most `rate` a second on average, bursts up to `burst` (the rate read at every take)."""

    def __init__(self, burst: float, now: float):
        self.tokens, self.t = burst, now

    def take(self, rate: float, burst: float, now: float) -> bool:
        self.tokens = min(burst, self.tokens + max(0.0, now - self.t) * rate)
        self.t = now
        if self.tokens >= 1.0:
            self.tokens -= 1.0
            return True
        return False


class SharedLimits:
    """One token bucket per (kind of client, kind of order), shared by every connection and address
    of that kind: a client cannot multiply the rate by opening connections or using more loopback
    addresses (127.0.0.0/8 is 16 million of them). rate(): the present rate a second (a live
    parameter); the burst is one second of it. Thread-safe (the WebSocket callbacks run in
    foxglove-sdk's threads, the HTTP handlers in their own)."""

    def __init__(self, rate):
        self.rate = rate
        self._buckets: Dict[Tuple[str, str], TokenBucket] = {}
        self._lock = threading.Lock()

    def take(self, client_kind: str, order_kind: str, now: float) -> bool:
        rate = float(self.rate())
        burst = max(1.0, rate)
        with self._lock:
            bucket = self._buckets.get((client_kind, order_kind))
            if bucket is None:
                bucket = self._buckets[(client_kind, order_kind)] = TokenBucket(burst, now)
            return bucket.take(rate, burst, now)


# A stand-alone live view follows /clock, which anyone on the domain may publish. Sim time runs at
# most MAX_SPEEDUP times the wall clock (a lockstep run of a light scenario; a replay at --rate),
# plus MAX_CLOCK_LEAD for a start at an offset and a starved subscriber's late catch-up.
MAX_SPEEDUP = 1000.0
MAX_CLOCK_LEAD_NS = 60_000_000_000


class ClockGuard:
    """The simulation time to stamp orders with, from /clock messages whose publisher the node
    cannot tell. A message ahead of the last one followed by more than MAX_CLOCK_LEAD_NS +
    MAX_SPEEDUP x the wall time since is not followed (observe() says why): a stranger's 2e9 s
    never becomes the stamp of an order. A message behind is followed (a new run, a replay started
    again): an order stamped for a past step is taken by a lockstep node at its next step, so a
    clock dragged back delays nothing; one stamped far ahead would be refused or wait."""

    def __init__(self):
        self.time_ns: Optional[int] = None
        self._wall: float = 0.0

    def observe(self, t_ns: int, wall: float) -> Optional[str]:
        """Follow t_ns (None) or say why not."""
        if self.time_ns is not None and t_ns > self.time_ns:
            allowed = MAX_CLOCK_LEAD_NS + MAX_SPEEDUP * max(0.0, wall - self._wall) * 1e9
            if t_ns - self.time_ns > allowed:
                return (f"/clock jumped from {self.time_ns * 1e-9:.3f} s to {t_ns * 1e-9:.3f} s in "
                        f"{max(0.0, wall - self._wall):.3f} s of wall time: not this run's clock, not followed")
        self.time_ns, self._wall = t_ns, wall
        return None
