"""Batch planning: slew tables and scene lists on local worker processes or a Dask cluster.

REQUESTS (a dict, or a YAML file holding one) is either

    slew_table:
      base: {scene keys without initial and final}
      targets: [{name: A, attitude: {axis: [..], angle: ..}}, {name: B, attitude: {quaternion: [..]}}]

(every ordered pair of distinct targets, rest to rest), or

    scenes: [path, {inline scene}, ...]

(paths relative to the REQUESTS file). An optional `options: {objective: .., steps: ..}` holds
plan()'s planning keywords for every solve. The table has one row per solve, columns
from, to, termination, cost, minimum_duration, solve_time_s, message (for `scenes`: from is the
index in the list, to the path, or the index again for an inline scene). Rows are appended as they
finish; a rerun with the same output skips the rows already there (resume); when every row is in,
the file is rewritten in request order, so a table does not depend on the order rows finished in.
A failed or invalid solve is a row with its verdict, never a crash. Work lost with a worker is run
again: by Dask itself on a cluster, by a new pool locally.
"""
import csv
import math
import os
import sys
from concurrent.futures import ProcessPoolExecutor, FIRST_COMPLETED, wait
from concurrent.futures.process import BrokenProcessPool

import yaml

import attitude_planner as ap

COLUMNS = ["from", "to", "termination", "cost", "minimum_duration", "solve_time_s", "message"]
# A solve whose worker died this many times is written as lost (a job that kills its worker
# every time would otherwise stop the table).
MAX_WORKER_LOSSES = 3


class Job:
    """One solve of a table: its row keys (`row_from`, `row_to`), the scene (a dict or a path)
    and the planning keywords."""

    def __init__(self, row_from, row_to, scene, options):
        self.row_from, self.row_to = str(row_from), str(row_to)
        self.scene, self.options = scene, options

    @property
    def key(self):
        return (self.row_from, self.row_to)


def _field_error(field, detail):
    return ap._input_error(field, detail)


def _slew_table_jobs(table, options):
    if not isinstance(table, dict) or set(table) - {"base", "targets"}:
        raise _field_error("slew_table", "expected {base: {...}, targets: [...]}, got %r" % (table,))
    base = table.get("base") or {}
    targets = table.get("targets") or []
    for key in ("initial", "final"):
        if key in base:
            raise _field_error("slew_table.base." + key, "not allowed (the targets give the ends)")
    names = []
    for i, target in enumerate(targets):
        if not isinstance(target, dict) or set(target) != {"name", "attitude"}:
            raise _field_error("slew_table.targets[%d]" % i,
                               "expected {name: .., attitude: {..}}, got %r" % (target,))
        names.append(str(target["name"]))
    if len(set(names)) != len(names) or len(names) < 2:
        raise _field_error("slew_table.targets", "need two or more distinct names, got %r" % names)
    rest = [0.0, 0.0, 0.0]
    jobs = []
    for a in targets:
        for b in targets:
            if a is b:
                continue
            scene = dict(base)
            scene["initial"] = {"attitude": a["attitude"], "angular_velocity": rest}
            scene["final"] = {"attitude": b["attitude"], "angular_velocity": rest}
            jobs.append(Job(a["name"], b["name"], scene, options))
    return jobs


def _scene_list_jobs(scenes, options, base_dir):
    if not isinstance(scenes, list) or not scenes:
        raise _field_error("scenes", "expected a non-empty list of paths or scenes, got %r"
                           % (scenes,))
    jobs = []
    for i, scene in enumerate(scenes):
        if isinstance(scene, str):
            jobs.append(Job(i, scene, os.path.join(base_dir, scene), options))
        elif isinstance(scene, dict):
            jobs.append(Job(i, i, scene, options))
        else:
            raise _field_error("scenes[%d]" % i, "expected a path or a scene, got %r" % (scene,))
    return jobs


def jobs_of(requests, base_dir="."):
    """The solves of REQUESTS (a dict, or the path of a YAML file), in table order."""
    if isinstance(requests, (str, os.PathLike)):
        base_dir = os.path.dirname(os.path.abspath(requests))
        with open(requests) as f:
            requests = yaml.safe_load(f)
    if not isinstance(requests, dict):
        raise _field_error("requests", "expected a mapping, got %r" % (requests,))
    unknown = set(requests) - {"slew_table", "scenes", "options"}
    kinds = [k for k in ("slew_table", "scenes") if k in requests]
    if unknown or len(kinds) != 1:
        raise _field_error("requests", "expected exactly one of slew_table, scenes (and options), "
                           "got keys %s" % sorted(requests))
    options = requests.get("options") or {}
    if not isinstance(options, dict):
        raise _field_error("options", "expected a mapping of plan() keywords, got %r" % (options,))
    # A batch runs one solve per core already: each solve on one thread (plan_maneuver --threads).
    options = dict(options)
    options.setdefault("threads", 1)
    if kinds[0] == "slew_table":
        return _slew_table_jobs(requests["slew_table"], options)
    return _scene_list_jobs(requests["scenes"], options, base_dir)


def _number(value):
    return "" if value is None or not math.isfinite(value) else "%.17g" % value


def solve_row(job):
    """Plans one job; its table row (a dict of COLUMNS). Never raises for a bad scene or a failed
    solve: the row carries the verdict."""
    row = {"from": job.row_from, "to": job.row_to, "cost": "", "minimum_duration": "",
           "solve_time_s": ""}
    try:
        result = ap.plan(ap.Problem(job.scene), **job.options)
    except ap.StepTooLargeError as e:
        row.update(termination="step_too_large", message=str(e))
    except ap.InputError as e:
        row.update(termination="invalid_input", message=str(e))
    except Exception as e:  # noqa: BLE001 -- a row with the error, never a lost table
        row.update(termination="not_converged", message="error: %s: %s" % (type(e).__name__, e))
    else:
        row.update(termination=result.termination, message=result.message,
                   cost=_number(result.cost),
                   minimum_duration=_number(result.minimum_duration or None),
                   solve_time_s=_number(result.solve_time_s))
    return row


class Table:
    """The output CSV: the keys of the rows already in it (resume), rows appended and flushed as
    they finish, rewritten in request order at the end."""

    def __init__(self, path):
        self.path = path
        self.rows = {}
        if os.path.exists(path) and os.path.getsize(path) > 0:
            with open(path, newline="") as f:
                reader = csv.DictReader(f)
                if reader.fieldnames != COLUMNS:
                    raise _field_error("--out", "'%s' has columns %s, expected %s"
                                       % (path, reader.fieldnames, COLUMNS))
                for row in reader:
                    self.rows[(row["from"], row["to"])] = row
        new = not self.rows
        self.file = open(path, "w" if new else "a", newline="")
        self.writer = csv.DictWriter(self.file, fieldnames=COLUMNS)
        if new:
            self.writer.writeheader()
            self.file.flush()

    def add(self, row):
        self.rows[(row["from"], row["to"])] = row
        self.writer.writerow(row)
        self.file.flush()  # a row written is a row kept, whatever happens next

    def finish(self, jobs):
        """Rewrites the file in the order of `jobs` if every job has its row (atomically)."""
        self.file.close()
        if any(job.key not in self.rows for job in jobs):
            return
        temporary = self.path + ".sorting"
        with open(temporary, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=COLUMNS)
            writer.writeheader()
            for job in jobs:
                writer.writerow(self.rows[job.key])
        os.replace(temporary, self.path)


def _lost_row(job, why="the worker running this solve was lost %d times" % MAX_WORKER_LOSSES):
    return {"from": job.row_from, "to": job.row_to, "termination": "not_converged", "cost": "",
            "minimum_duration": "", "solve_time_s": "", "message": why}


def _run_local(jobs, workers, done):
    """Yields the rows of `jobs` from `workers` local processes; a pool broken by a lost worker is
    replaced and its unfinished jobs run again (a job that kills its worker every time gets a
    lost row)."""
    pending = list(jobs)
    losses = {}
    while pending:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            window = {}
            queue = list(reversed(pending))
            try:
                while queue or window:
                    while queue and len(window) < 4 * workers:
                        job = queue.pop()
                        window[pool.submit(solve_row, job)] = job
                    finished, _ = wait(window, return_when=FIRST_COMPLETED)
                    for future in finished:
                        job = window.pop(future)
                        yield future.result()
                        done.add(job.key)
                pending = []
            except BrokenProcessPool:
                pending = [job for job in jobs if job.key not in done]
                for job in window.values():
                    losses[job.key] = losses.get(job.key, 0) + 1
                for job in [j for j in pending if losses.get(j.key, 0) >= MAX_WORKER_LOSSES]:
                    yield _lost_row(job)
                    done.add(job.key)
                pending = [job for job in pending if job.key not in done]


def _run_dask(jobs, scheduler, done):
    """Yields the rows of `jobs` computed on the Dask cluster at `scheduler` (an address, or a
    distributed.Client). The scheduler reruns the tasks of a lost worker on the others."""
    from distributed import Client, as_completed

    client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
    try:
        futures = client.map(solve_row, jobs, pure=False)
        job_of = dict(zip(futures, jobs))
        for future in as_completed(futures):
            job = job_of[future]
            try:
                row = future.result()
            except Exception as e:  # noqa: BLE001 -- e.g. KilledWorker: its workers kept dying
                row = _lost_row(job, "error on the cluster: %s: %s" % (type(e).__name__, e))
            yield row
            done.add(job.key)
    finally:
        if client is not scheduler:
            client.close()


def plan_batch(requests, out, workers=None, scheduler=None, progress=True, on_row=None):
    """Plans every solve of REQUESTS (a dict, or a YAML path) into the CSV `out`; returns the
    number of rows written by this call. `workers`: local processes (default: all cores);
    `scheduler`: a Dask scheduler address or Client (then `workers` is unused); `progress`: a
    progress bar (done/total, rate) on stderr; `on_row(row)`: called after each row is written.
    A rerun with the same `out` skips the rows already in it."""
    jobs = jobs_of(requests)
    table = Table(out)
    todo = [job for job in jobs if job.key not in table.rows]
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=len(jobs), initial=len(jobs) - len(todo), unit="solve",
                   file=sys.stderr, dynamic_ncols=True)
    done = set()
    try:
        rows = (_run_dask(todo, scheduler, done) if scheduler is not None
                else _run_local(todo, workers or os.cpu_count() or 1, done))
        for row in rows:
            table.add(row)
            if bar is not None:
                bar.update(1)
            if on_row is not None:
                on_row(row)
    finally:
        if bar is not None:
            bar.close()
        table.finish(jobs)
    return len(done)


def main(argv=None):
    import argparse

    parser = argparse.ArgumentParser(
        prog="plan_batch", description="Plan a slew table or a list of scenes into one CSV "
        "(columns %s); a rerun with the same --out resumes." % ", ".join(COLUMNS))
    parser.add_argument("requests", help="REQUESTS.yaml: slew_table: {base, targets} or scenes: [..]")
    parser.add_argument("--out", required=True, help="TABLE.csv (appended to: resumes)")
    parser.add_argument("--workers", type=int, default=None,
                        help="local worker processes (default: the number of cores)")
    parser.add_argument("--scheduler", default=None,
                        help="address of a dask.distributed scheduler: run there instead")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    if args.workers is not None and args.workers < 1:
        parser.error("--workers: must be >= 1, got %d" % args.workers)
    try:
        plan_batch(args.requests, args.out, workers=args.workers, scheduler=args.scheduler,
                   progress=not args.no_progress)
    except (ap.InputError, OSError) as e:
        print("plan_batch: %s" % e, file=sys.stderr)
        return 1
    return 0
