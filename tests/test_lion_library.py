"""The workflow on one pose of the lion library (../shared/data/lion-poses; the session's lion run, conftest):
the intersection counts of its key frames, its disk use, and its repaired files (every pose and every repair: make
bench)."""

import json

import h5py
import numpy as np
import pytest

from conftest import LION_POSES, shared_library

pytestmark = pytest.mark.pipeline


@pytest.mark.data
def test_lion_library(lion_run):
    lib = shared_library("lion-poses")
    results = lion_run / "results" / "lion-poses"
    target_counts = {"lion-01": 465, "lion-04": 717, "lion-07": 903}  # SOURCES.md, independent check
    for pose in LION_POSES:
        with h5py.File(results / pose / "classify.h5", "r") as fh:
            counts = fh["intersecting_faces"][()]
            assert counts[0] == 138 and counts[-1] == target_counts.get(pose, counts[-1])
            assert max(counts[1:-1]) <= max(counts[0], counts[-1])  # no tearing in the key frames
            assert fh["mask"][()].sum() > 0.5 * len(fh["mask"])
        size = sum(f.stat().st_size for f in (results / pose).rglob("*") if f.is_file())
        assert size <= 25e6 and not (results / pose / "fit.checkpoint").exists(), (pose, size)  # issue 29: disk
    _check_repaired_library(lion_run, lib, "lion-poses")


def _check_repaired_library(work, lib, name):
    """Repaired files keep the input's faces; fewer intersections than the target; V_C reproduced
    within 1e-3 d on average and 5e-3 d at most; new intersecting faces only inside regions copied
    from the target where key frames pass through each other (issue 4's acceptance)."""
    from posefix.io.meshes import read_mesh
    summary = json.loads((work / "reports" / name / "summary.json").read_text())
    for e in summary["poses"]:
        source = next(lib.glob(f"{e['pose']}.*"))
        V_tgt, F = read_mesh(source)
        V, F2 = read_mesh(work / "results" / name / "repaired" / source.name)
        assert np.array_equal(F, F2) and V.shape == V_tgt.shape
        i = e["intersecting_faces"]
        assert i["repaired"] < i["target"] or i["repaired"] <= i["reference"], e["pose"]
        assert e["deviation"]["constrained_mean"] <= 1e-3, e["pose"]
        assert e["deviation"]["constrained_max"] <= 5e-3, e["pose"]
        assert i["repaired_new"] == i["repaired_new_in_fallback"], e["pose"]
