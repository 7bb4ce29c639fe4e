"""One run of a study, as a Dask task does it on its worker: the run's scenario written out, a ROS
domain reserved from the domain coordinator on that machine, `run_scenario` run on it (its
installed console script, the one-process layout: the same code path as by hand, and the
cheapest), then analyze's own code on the recording (recording.analysis.main, --no-figures) and
the measures taken from its summary.json. A failure is a row with the exit status and the message,
never an exception: the study goes on.
"""
from __future__ import annotations

import ctypes
import json
import math
import os
import shutil
import signal
import socket
import subprocess
import time
from typing import Any, Dict, Optional

import yaml

from studies.study_file import get_value

# the domain is this run's alone (reserved on this machine, discovery kept on it): the runner's
# 3 s look for another run on the domain shortened (scenario_runner.conductor)
DOMAIN_CHECK_WAIT = "0.5"
MESSAGE_TAIL = 2000  # characters of a failed run's output kept in the table
# a worker's runs take their domains from this range ("LO-HI", reserved with the domain coordinator
# on its machine) instead of the coordinator's 1-100: workers sharing a machine's shared memory
# (network namespaces) or other ROS work on it keep apart
DOMAIN_RANGE_VARIABLE = "TUGSIM_STUDY_DOMAINS"


def domain_selector():
    """The domain coordinator's selector of DOMAIN_RANGE_VARIABLE's range; None (its own 1-100)
    without it. ValueError naming a bad value."""
    text = os.environ.get(DOMAIN_RANGE_VARIABLE)
    if not text:
        return None
    lo, _, hi = text.partition("-")
    try:
        lo, hi = int(lo), int(hi)
    except ValueError:
        lo = hi = -1
    if not 0 <= lo <= hi <= 232:
        raise ValueError(f"{DOMAIN_RANGE_VARIABLE}={text!r}: expected LO-HI, ROS domain ids 0 <= LO <= HI <= 232")
    count = iter(range(10 ** 9))
    return lambda: lo + next(count) % (hi - lo + 1)


def _die_with_parent() -> None:
    """The run stops when its worker dies (a killed worker's run is rerun elsewhere by Dask)."""
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except OSError:
        pass


def _where() -> str:
    """The Dask worker's address (the machine and worker that made the run), else the host name."""
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):
        return socket.gethostname()


def _tail(text: str) -> str:
    text = text.strip()
    return text if len(text) <= MESSAGE_TAIL else "..." + text[-MESSAGE_TAIL:]


def run_command(scenario_file: str, recording: str, duration: Optional[float] = None) -> list:
    """The run_scenario command of a study's run (what the table's runs are checked against)."""
    from scenario_runner.run_nodes import executable_path
    return ([executable_path("scenario_runner", "run_scenario"), scenario_file, "--output", recording, "--quiet",
             "--layout", "one_process"] + (["--duration", repr(float(duration))] if duration else []))


def analyze_arguments(recording: str, folder: str, sea_window: Optional[list] = None) -> list:
    """analyze's command line of a study's run (no figures: the measures only)."""
    window = ["--sea-window", repr(float(sea_window[0])), repr(float(sea_window[1]))] if sea_window else []
    return [recording, "-o", folder, "--no-figures", "--quiet", *window]


def measures_of(summary: dict, measures: Dict[str, str]) -> Dict[str, Any]:
    """{name: value} of analyze's summary; NaN where the summary has no such value (a run without
    a turn has no tactical diameter)."""
    out = {}
    for name, key in measures.items():
        try:
            value = get_value(summary, key)
        except KeyError:
            value = None
        if isinstance(value, bool):
            value = float(value)
        out[name] = float(value) if isinstance(value, (int, float)) else math.nan
    return out


def execute_run(run: str, scenario: Dict[str, Any], folder: str, measures: Dict[str, str],
                keep_recording: bool = False, timeout: Optional[float] = None,
                sea_window: Optional[list] = None, duration: Optional[float] = None) -> Dict[str, Any]:
    """Runs one scenario mapping in `folder` (made; removed afterwards unless keep_recording)
    and measures it: {status, exit_status, message, <measures>, wall_time, host, recording}."""
    from domain_coordinator import domain_id
    from recording.analysis import main as analyze
    start = time.monotonic()
    os.makedirs(folder, exist_ok=True)
    scenario_file = os.path.join(folder, "scenario.yaml")
    recording = os.path.join(folder, "run.mcap")
    with open(scenario_file, "w", encoding="utf-8") as f:
        yaml.safe_dump(scenario, f, sort_keys=False)
    row: Dict[str, Any] = {"status": "ok", "exit_status": 0, "message": "", "host": _where(),
                           "recording": os.path.abspath(recording) if keep_recording else ""}
    row.update({name: math.nan for name in measures})
    with domain_id(domain_selector()) as domain:
        env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
                   TUGSIM_DOMAIN_CHECK_WAIT=DOMAIN_CHECK_WAIT, PYTHONUNBUFFERED="1")
        env.pop("ROS_STATIC_PEERS", None)
        try:
            proc = subprocess.run(run_command(scenario_file, recording, duration), env=env, capture_output=True, text=True,
                                  timeout=timeout, preexec_fn=_die_with_parent)
            status, output = proc.returncode, proc.stderr or proc.stdout
        except subprocess.TimeoutExpired as exc:
            status, output = -1, f"run_scenario: no end after {timeout:g} s (killed)\n{exc.stderr or ''}"
    if status != 0:
        row.update(status="failed", exit_status=status, message=_tail(f"run_scenario exit {status}: {output}"))
    else:
        analysis = os.path.join(folder, "analysis")
        status = analyze(analyze_arguments(recording, analysis, sea_window))
        if status != 0:
            row.update(status="failed", exit_status=status, message=f"analyze exit {status} on {recording}")
        else:
            with open(os.path.join(analysis, "summary.json"), encoding="utf-8") as f:
                row.update(measures_of(json.load(f), measures))
    row["wall_time"] = time.monotonic() - start
    if not keep_recording:
        shutil.rmtree(folder, ignore_errors=True)
    row["run"] = run
    return row
