"""Identities and clock of bridge equipment as a scenario gives them (ROS-free): the MMSI a
vessel's AIS transponder sends, and the UTC the NMEA sentences start from. The scenario checks
them before any node starts; bridge_instruments formats the sentences with them."""
from __future__ import annotations

import datetime as _dt
from typing import Optional

NMEA_UDP_PORT = 10110  # the port NMEA 0183 over UDP uses by convention (OpenCPN, gpsd)
DEFAULT_UTC_START = "2026-06-01T08:00:00Z"  # UTC of simulation time 0 unless a scenario says

def parse_utc(text: str) -> _dt.datetime:
    """An ISO 8601 UTC time ('2026-06-01T08:00:00Z'), whole hundredths of a second."""
    s = text.strip()
    if s.endswith("Z") or s.endswith("z"):
        s = s[:-1] + "+00:00"
    d = _dt.datetime.fromisoformat(s)
    if d.tzinfo is None:
        d = d.replace(tzinfo=_dt.timezone.utc)
    d = d.astimezone(_dt.timezone.utc)
    if d.microsecond % 10000:
        raise ValueError(f"{text!r}: give whole hundredths of a second")
    return d


def check_mmsi(value: int) -> Optional[str]:
    """Why an MMSI cannot be used (None if it can): nine digits, 100 000 000 .. 999 999 999."""
    if isinstance(value, bool) or not isinstance(value, int) or not 100_000_000 <= value <= 999_999_999:
        return f"{value!r} is not a nine-digit MMSI"
    return None
