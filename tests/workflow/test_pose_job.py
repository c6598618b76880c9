"""The pose job (python -m posefix.workflow.pose_job), which the Blender add-on starts: one JSON line per pose as it
finishes, the repaired poses as posefix.repair_pose gives them, a pose that cannot be repaired as its line while the
others go on, and a job that cannot run as one line and exit 1."""

import json
import subprocess
import sys

import numpy as np

import posefix
from posefix.workflow.demo import demo_library


def test_a_job_repairs_its_poses_as_repair_pose_and_says_so_pose_by_pose(tmp_path):
    V, F, poses = demo_library(around=12)
    bad = poses["demo-02"].copy()
    bad[5] = np.nan
    np.savez(tmp_path / "job.npz", reference=V, faces=F, poses=np.stack([poses["demo-01"], bad]),
             names=np.array(["smile", "frown"]))
    proc = subprocess.run([sys.executable, "-m", "posefix.workflow.pose_job", tmp_path, "--cores", "1"],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = [json.loads(line) for line in proc.stdout.splitlines()]
    assert [(line["name"], line["status"], line["done"], line["total"]) for line in lines] == \
        [("smile", "ok", 1, 2), ("frown", "error", 2, 2)]
    assert lines[1]["reason"] == "1 of 362 rows with NaN or infinite values (first: row 5)"
    assert lines[0]["intersecting_faces"]["repaired_new"] == 0 and lines[0]["intersecting_faces"]["target"] > 0
    assert np.array_equal(np.load(tmp_path / "repaired-0.npy"), posefix.repair_pose(V, F, poses["demo-01"]).V)
    assert not (tmp_path / "repaired-1.npy").exists()
    assert json.loads((tmp_path / "results.json").read_text()) == [
        {k: v for k, v in line.items() if k not in ("done", "total")} for line in lines]


def test_a_job_that_cannot_run_is_one_line_and_exit_1(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "posefix.workflow.pose_job", tmp_path / "nowhere"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1
    assert proc.stderr.strip().splitlines()[-1].startswith("posefix: error: [Errno 2] No such file or directory")
