"""Run a study: a scenario swept over axes and seeds on Dask, its measures in one table.

    ros2 run studies study tow_length_engine_order.yaml -o output/studies/tow_length

The study file (studies/study_file.py has the format) is checked before any run starts. Its runs
go to Dask (distributed): an embedded LocalCluster of one single-threaded worker per core (or
--workers N), or an existing cluster with --scheduler ADDRESS (workers started there with the
project's environment: `dask worker ADDRESS --nthreads 1`). Each run is isolated on its worker
(its own ROS domain from that machine's domain coordinator) and made by run_scenario and analyze
(studies/one_run.py). The table is written as the runs come in, so a study stopped half-way is
resumed by the same command: runs already in the table without failure are not run again. A
failed run is a row with its exit status and message; the study goes on. A run whose worker dies
is run again on another (Dask reschedules it).

Writes to the output folder (default output/studies/<study name>):
  results.parquet     one row per run: run, configuration, sample, the axes' values (a column per
                      key), status (ok / failed), exit_status, message, the measures, wall_time,
                      host (the Dask worker's address), recording (with --keep-recordings: runs/<run>/run.mcap beside it)
  statistics.parquet  one row per configuration: the measures' count, mean, std, min, max over
  statistics.csv      its seeds and, with `extremes`, the Gumbel fit and most probable maximum
  figures/<measure>.png   each measure against the axes
Exit status: 0 every run done; 1 the table is complete but some runs failed; 2 invalid study
file, output folder or scheduler (nothing run).
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import os
import sys
import tempfile
import uuid
from typing import Callable, List, Optional

from studies.extremes import configuration_statistics
from studies.figures import measure_figures
from studies.study_file import StudyError, StudyPlan, plan_study, load_study

EXIT_OK, EXIT_FAILED_RUNS, EXIT_INVALID = 0, 1, 2
RESULTS, STATISTICS = "results.parquet", "statistics.parquet"


@dataclasses.dataclass
class StudyResult:
    plan: StudyPlan
    table: "object"         # pandas.DataFrame: one row per run
    statistics: "object"    # pandas.DataFrame: one row per configuration
    folder: str
    ran: int                # runs made by this call (the others were in the table already)
    figures: List[str]

    @property
    def failed(self) -> int:
        return int((self.table["status"] != "ok").sum())


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="study", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="Exit status: 0 every run done; 1 some runs failed (recorded in the table); "
                                       "2 invalid study file, output or scheduler.")
    p.add_argument("study", help="study file (YAML), or a name in share/studies/examples")
    p.add_argument("-o", "--output", help="output folder (default output/studies/<study name>)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask scheduler, e.g. tcp://10.0.0.1:8786 "
                                                          "(default: an embedded LocalCluster)")
    p.add_argument("--workers", type=int, help="workers of the embedded LocalCluster (default: one per core)")
    p.add_argument("--keep-recordings", action="store_true", help="keep each run's MCAP recording and analysis")
    p.add_argument("--timeout", type=float, help="s after which a run is stopped and recorded as failed")
    p.add_argument("--plan", action="store_true", help="check the study and list its runs; run nothing")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def print_plan(path: str) -> None:
    """The study checked and its runs listed, one line each (what --plan prints)."""
    with tempfile.TemporaryDirectory(prefix="study-check-") as scratch:
        plan = plan_study(path, scratch)
    print(f"study {plan.study.name}: {len(plan.runs)} runs of {plan.study.scenario}, "
          f"{plan.study.duration or plan.runs[0].scenario['duration']} s each")
    for r in plan.runs:
        values = ", ".join(f"{k} = {v!r}" for k, v in r.values.items())
        print(f"  {r.run}  configuration {r.configuration} sample {r.sample}: {values}")


def study_path(name: str) -> str:
    from sim_math.data_files import resolve
    return resolve("studies", "examples", name)


def _columns(plan: StudyPlan) -> List[str]:
    keys = plan.axis_keys + ([plan.study.seeds.key] if plan.study.seeds else [])
    return (["run", "configuration", "sample"] + keys + ["status", "exit_status", "message"]
            + list(plan.study.measures) + ["wall_time", "host", "recording"])


def _earlier_rows(path: str, plan: StudyPlan) -> list:
    """The rows of an earlier call of this study (same runs, no failure): not run again."""
    import pandas as pd
    if not os.path.exists(path):
        return []
    old = pd.read_parquet(path)
    wanted = {r.run for r in plan.runs}
    columns = _columns(plan)
    if list(old.columns) != columns:
        return []  # another study's table (other axes or measures): every run made anew
    keep = old[(old["status"] == "ok") & old["run"].isin(wanted)]
    return keep.to_dict("records")


def _write_table(rows: list, plan: StudyPlan, path: str):
    """The table, runs in plan order, written atomically (a stopped study leaves a readable one)."""
    import pandas as pd
    order = {r.run: i for i, r in enumerate(plan.runs)}
    table = pd.DataFrame(sorted(rows, key=lambda row: order[row["run"]]), columns=_columns(plan))
    table["exit_status"] = table["exit_status"].astype("int64")
    tmp = path + ".part"
    table.to_parquet(tmp, index=False)
    os.replace(tmp, path)
    return table


def _client(scheduler: Optional[str], workers: Optional[int]):
    """(dask Client, cluster or None): the scheduler's, or an embedded LocalCluster."""
    from distributed import Client, LocalCluster
    if scheduler:
        return Client(scheduler, timeout="20s"), None
    cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                           dashboard_address=":0", silence_logs=40)
    return Client(cluster), cluster


def _run_all(plan: StudyPlan, todo, client, folder: str, rows: list, keep: bool, timeout: Optional[float],
             progress, table_path: str) -> None:
    from distributed import as_completed
    from studies.one_run import execute_run
    by_key = {}
    for r in todo:
        key = f"study-{plan.study.name}-{r.run}-{uuid.uuid4().hex[:8]}"
        future = client.submit(execute_run, r.run, r.scenario, os.path.join(folder, "runs", r.run),
                               dict(plan.study.measures), keep, timeout, plan.study.sea_window,
                               plan.study.duration, key=key, pure=False)
        by_key[future.key] = (future, r)
    for future in as_completed([f for f, _ in by_key.values()]):
        r = by_key[future.key][1]
        try:
            row = future.result()
        except Exception as exc:  # noqa: BLE001 - e.g. KilledWorker: its workers died again and again
            row = {"run": r.run, "status": "failed", "exit_status": -1, "host": "", "recording": "",
                   "message": f"{type(exc).__name__}: {exc}", "wall_time": math.nan,
                   **{m: math.nan for m in plan.study.measures}}
        row.update(run=r.run, configuration=r.configuration, sample=r.sample, **r.values)
        rows.append(row)
        _write_table(rows, plan, table_path)
        if progress is not None:
            progress.update(1)


def run_study(path: str, output: Optional[str] = None, scheduler: Optional[str] = None,
              workers: Optional[int] = None, keep_recordings: bool = False, timeout: Optional[float] = None,
              say: Callable[[str], None] = print, progress: bool = True) -> StudyResult:
    """The Python API of `study`: checks the study (StudyError before anything runs), runs what
    the table in `output` does not hold yet, writes table, statistics and figures. `path`: a
    study file, or the name of an installed example."""
    with tempfile.TemporaryDirectory(prefix="study-check-") as scratch:
        plan = plan_study(study_path(path), scratch)
    folder = os.path.abspath(output or os.path.join("output", "studies", plan.study.name))
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as exc:
        raise StudyError(f"output folder {folder}: {exc}") from None
    table_path = os.path.join(folder, RESULTS)
    rows = _earlier_rows(table_path, plan)
    done = {row["run"] for row in rows}
    todo = [r for r in plan.runs if r.run not in done]
    say(f"study {plan.study.name}: {len(plan.runs)} runs ({len(done)} already in {table_path}), "
        f"{len({r.configuration for r in plan.runs})} configuration(s)")
    if todo:
        try:
            client, cluster = _client(scheduler, workers)
        except (OSError, TimeoutError) as exc:
            raise StudyError(f"--scheduler {scheduler}: cannot reach it: {exc}") from None
        try:
            say(f"dask: {len(client.scheduler_info()['workers'])} worker(s); dashboard {client.dashboard_link}")
            bar = None
            if progress:
                from tqdm import tqdm
                bar = tqdm(total=len(todo), unit="run", desc=plan.study.name, file=sys.stderr, mininterval=0.5)
            _run_all(plan, todo, client, folder, rows, keep_recordings, timeout, bar, table_path)
            if bar is not None:
                bar.close()
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    return _finish(plan, rows, folder, table_path, len(todo), say)


def _finish(plan: StudyPlan, rows: list, folder: str, table_path: str, ran: int, say) -> StudyResult:
    try:
        os.rmdir(os.path.join(folder, "runs"))  # left empty when no recording was kept
    except OSError:
        pass
    table = _write_table(rows, plan, table_path)
    stats = configuration_statistics(table, plan.axis_keys, list(plan.study.measures), plan.study.extremes,
                                     plan.run_duration)
    stats.to_parquet(os.path.join(folder, STATISTICS), index=False)
    stats.to_csv(os.path.join(folder, "statistics.csv"), index=False)
    figures = measure_figures(table, stats, plan.axis_keys, dict(plan.study.measures), os.path.join(folder, "figures"),
                              plan.study.extremes)
    result = StudyResult(plan, table, stats, folder, ran, figures)
    say(f"study {plan.study.name}: {len(table)} runs in {table_path} ({result.failed} failed); statistics of "
        f"{len(stats)} configuration(s) and {len(figures)} figure(s) in {folder}")
    for row in table[table["status"] != "ok"].itertuples():
        say(f"  failed run {row.run} (exit {row.exit_status}): {row.message.splitlines()[0] if row.message else ''}")
    return result


def main(argv: Optional[List[str]] = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = build_parser().parse_args(argv)
    if args.workers is not None and args.workers < 1:
        sys.stderr.write(f"study: --workers {args.workers}: expected 1 or more\n")
        return EXIT_INVALID
    if args.timeout is not None and not (math.isfinite(args.timeout) and args.timeout > 0):
        sys.stderr.write(f"study: --timeout {args.timeout!r}: expected a positive number of seconds\n")
        return EXIT_INVALID
    try:
        if args.plan:
            print_plan(study_path(args.study))
            return EXIT_OK
        result = run_study(args.study, args.output, args.scheduler, args.workers, args.keep_recordings,
                           args.timeout, progress=not args.quiet)
    except StudyError as exc:
        sys.stderr.write(f"study: invalid study:\n{exc}\n")
        return EXIT_INVALID
    return EXIT_FAILED_RUNS if result.failed else EXIT_OK


__all__ = ["StudyResult", "load_study", "main", "run_study"]

if __name__ == "__main__":
    sys.exit(main())
