"""Batch planning (attitude_planner.batch, plan_batch): a slew table on local workers, resume,
rows with verdicts for bad scenes, a lost local worker, and a 2-worker Dask LocalCluster with one
worker killed mid-run giving every row, equal to the local run. Small tables: this checks the
bookkeeping, the rates are measured by scripts/slew_table_benchmark."""
import csv
import multiprocessing
import os
import signal
import subprocess
import tempfile
import unittest

import yaml

import attitude_planner as ap
from attitude_planner import batch
from support import REPO, tool


BASE = {"inertia": [10, 12, 14], "steps": 16, "scheme": "second_order",
        "objective": "minimum_time", "constraints": [{"max_torque_norm": 1.0}]}
TARGETS = [{"name": "A", "attitude": {"axis": [1, 0, 0], "angle": 0.0}},
           {"name": "B", "attitude": {"axis": [0, 1, 0], "angle": 0.6}},
           {"name": "C", "attitude": {"quaternion": [0.9, 0.0, 0.0, 0.4358898943540674]}},
           {"name": "D", "attitude": {"axis": [1, 1, 0], "angle": 0.9}}]


def table(n_targets):
    return {"slew_table": {"base": BASE, "targets": TARGETS[:n_targets]}}


def read(path):
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        return reader.fieldnames, list(reader)


def comparable(rows):
    """Rows without the wall-clock column, keyed by (from, to)."""
    return {(r["from"], r["to"]): {k: v for k, v in r.items() if k != "solve_time_s"}
            for r in rows}


class LocalTables(unittest.TestCase):

    def setUp(self):
        self.directory = tempfile.TemporaryDirectory()
        self.out = os.path.join(self.directory.name, "table.csv")

    def tearDown(self):
        self.directory.cleanup()

    def test_every_ordered_pair_with_the_plan_of_each(self):
        written = batch.plan_batch(table(3), self.out, workers=2, progress=False)
        columns, rows = read(self.out)
        self.assertEqual(columns, ["from", "to", "termination", "cost", "minimum_duration",
                                   "solve_time_s", "message"])
        self.assertEqual(written, 6)
        self.assertEqual([(r["from"], r["to"]) for r in rows],
                         [("A", "B"), ("A", "C"), ("B", "A"), ("B", "C"), ("C", "A"), ("C", "B")])
        for row in rows:
            self.assertEqual(row["termination"], "converged", row["message"])
        # Row B -> C is the plan of that scene, to the last digit.
        scene = dict(BASE, initial={"attitude": TARGETS[1]["attitude"],
                                    "angular_velocity": [0.0, 0.0, 0.0]},
                     final={"attitude": TARGETS[2]["attitude"],
                            "angular_velocity": [0.0, 0.0, 0.0]})
        direct = ap.plan(scene)
        row = rows[3]
        self.assertEqual(row["cost"], "%.17g" % direct.cost)
        self.assertEqual(row["minimum_duration"], "%.17g" % direct.minimum_duration)
        # A -> B and B -> A: the same rest-to-rest slew reversed, the same least time.
        self.assertAlmostEqual(float(rows[0]["minimum_duration"]),
                               float(rows[2]["minimum_duration"]), places=6)

    def test_rerun_resumes(self):
        batch.plan_batch(table(3), self.out, workers=1, progress=False)
        _, full = read(self.out)
        with open(self.out) as f:
            head = f.readlines()[:3]  # the header and two rows: a run stopped there
        with open(self.out, "w") as f:
            f.writelines(head)
        solved = []
        written = batch.plan_batch(table(3), self.out, workers=2, progress=False,
                                   on_row=solved.append)
        self.assertEqual(written, 4)
        self.assertNotIn(("A", "B"), [(r["from"], r["to"]) for r in solved])
        _, resumed = read(self.out)
        self.assertEqual(comparable(resumed), comparable(full))
        self.assertEqual(batch.plan_batch(table(3), self.out, workers=2, progress=False), 0)

    def test_bad_scenes_are_rows_with_their_verdict(self):
        requests = {"scenes": [os.path.join(REPO, "scenes", "rest_to_rest.yaml"),
                               dict(BASE, stepz=3), "no_such_scene.yaml"]}
        path = os.path.join(self.directory.name, "requests.yaml")
        with open(path, "w") as f:
            yaml.safe_dump(requests, f)
        done = subprocess.run([tool("plan_batch"), path, "--out", self.out, "--workers", "2",
                               "--no-progress"], stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, universal_newlines=True)
        self.assertEqual(done.returncode, 0, done.stdout)
        _, rows = read(self.out)
        by_from = {r["from"]: r for r in rows}
        self.assertEqual(by_from["0"]["termination"], "converged")
        self.assertEqual(by_from["1"]["termination"], "invalid_input")
        self.assertIn("stepz", by_from["1"]["message"])
        self.assertEqual(by_from["2"]["termination"], "invalid_input")
        self.assertIn("no_such_scene.yaml", by_from["2"]["message"])

    def test_a_lost_local_worker_loses_no_row(self):
        batch.plan_batch(table(3), self.out, workers=1, progress=False)
        _, reference = read(self.out)
        os.remove(self.out)
        killed = []

        def kill_a_worker(row):
            if not killed:
                victim = multiprocessing.active_children()[0]
                os.kill(victim.pid, signal.SIGKILL)
                killed.append(victim.pid)

        batch.plan_batch(table(3), self.out, workers=2, progress=False, on_row=kill_a_worker)
        _, rows = read(self.out)
        self.assertEqual(len(killed), 1)
        self.assertEqual(comparable(rows), comparable(reference))


class DaskCluster(unittest.TestCase):

    def test_a_killed_worker_loses_no_row_and_the_table_equals_the_local_one(self):
        from distributed import Client, LocalCluster

        with tempfile.TemporaryDirectory() as directory:
            local = os.path.join(directory, "local.csv")
            remote = os.path.join(directory, "dask.csv")
            batch.plan_batch(table(4), local, workers=2, progress=False)
            with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                              dashboard_address=None) as cluster, Client(cluster) as client:
                pids = client.run(os.getpid)
                self.assertEqual(len(pids), 2)
                killed = []

                def kill_a_worker(row):
                    if not killed:
                        pid = sorted(pids.values())[0]
                        os.kill(pid, signal.SIGKILL)
                        killed.append(pid)

                written = batch.plan_batch(table(4), remote, scheduler=cluster.scheduler_address,
                                           progress=False, on_row=kill_a_worker)
            self.assertEqual(killed and written, 12)
            local_columns, local_rows = read(local)
            dask_columns, dask_rows = read(remote)
            self.assertEqual(dask_columns, local_columns)
            # Row for row: the same order (request order) and the same values but the wall time.
            self.assertEqual([comparable([r]) for r in dask_rows],
                             [comparable([r]) for r in local_rows])


if __name__ == "__main__":
    unittest.main()
