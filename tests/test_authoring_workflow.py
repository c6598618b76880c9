"""Libraries authored by the workflow's own rules (from the demo rig, the demo pose script and the demo's marker
tracks), then repaired by it."""

import json

import h5py
import numpy as np
import pytest

from conftest import snakemake

pytestmark = pytest.mark.pipeline


def repair_options(name):
    """The target and config of the repair of authored library ``name``: S0 alone (the session's demo run checks
    the other repairs) up to the summary, with one downstream step (no figures, no viewer)."""
    return f"reports/{name}/summary.json", "--config", "repairs=[]", "downstream={'max_iters': 1}"


def test_author_a_library_from_the_demo_rig_and_repair_it(tmp_path):
    """`snakemake skeletal_pose` (S1: the demo rig -> <pose>-ssd/-variational/-flow), then the S0 repair of one of them.
    Called by its name before 2026-12 (`author`), with its config section's name before 2026-12 (`skeletal_pose`),
    which still work for a release and say the new ones."""
    proc = snakemake(tmp_path, "author", "--config", "skeletal_pose={'max_iters': 20}")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "posefix: rule 'author' is now 'skeletal_pose'" in proc.stderr
    assert ("posefix: config key 'skeletal_pose' is now 'medial.pose and medial.skeleton' (the old key goes in the "
            "next release)") in proc.stderr.splitlines()
    library = tmp_path / "data" / "authored" / "demo-limb"
    names = sorted(p.name for p in library.iterdir() if not p.name.startswith("."))  # and .snakemake_timestamp
    assert names[0] == "demo-01-flow.obj" and "demo-limb-reference.obj" in names and len(names) == 13
    with h5py.File(tmp_path / "results" / "authored" / "demo-limb" / "skeletal_pose.h5", "r") as fh:
        intersecting = fh["intersecting"][()]
    assert intersecting.shape == (4, 3) and intersecting[1, 2] < intersecting[1, 1]  # demo-02: flow < variational
    proc = snakemake(tmp_path, *repair_options("demo-limb"), f"library={library}", "poses=demo-02-flow")
    assert proc.returncode == 0, proc.stderr[-3000:]
    entry = json.loads((tmp_path / "reports" / "demo-limb" / "summary.json").read_text())["poses"][0]
    assert entry["pose"] == "demo-02-flow" and entry["intersecting_faces"]["repaired_new"] == 0
    assert (tmp_path / "results" / "demo-limb" / "repaired" / "demo-02-flow.obj").exists()


def test_author_a_library_from_the_demo_pose_script_and_repair_it(tmp_path):
    """`snakemake volumetric_pose` (S4: the demo pose script -> vol-bend, vol-fold, vol-twist), then the S0
    repair of the bent one (alone: the session's demo run checks the other repairs; the folded one, 525 faces
    intersecting, took 93 s of stages in a loaded run against the bent one's 15 s)."""
    proc = snakemake(tmp_path, "volumetric_pose", "--config", "volumetric={'pose': {'tet_vertices': 400}}")
    assert proc.returncode == 0, proc.stderr[-3000:]
    library = tmp_path / "data" / "authored" / "demo-limb-volumetric"
    names = sorted(p.name for p in library.iterdir() if not p.name.startswith("."))
    assert names == ["demo-limb-volumetric-reference.obj", "vol-bend.obj", "vol-fold.obj", "vol-twist.obj"]
    proc = snakemake(tmp_path, *repair_options("demo-limb-volumetric"), f"library={library}", "poses=vol-bend")
    assert proc.returncode == 0, proc.stderr[-3000:]
    entry = json.loads((tmp_path / "reports" / "demo-limb-volumetric" / "summary.json").read_text())["poses"][0]
    assert entry["pose"] == "vol-bend" and entry["intersecting_faces"]["target"] > 0
    assert entry["intersecting_faces"]["repaired_new"] == entry["intersecting_faces"]["repaired_new_in_fallback"]
    assert (tmp_path / "results" / "demo-limb-volumetric" / "repaired" / "vol-bend.obj").exists()


def test_animate_a_library_from_the_demo_markers_and_repair_it(tmp_path):
    """`snakemake volumetric_animate` (S4 §3.2: 8 markers, 13 frames of the demo limb bending) gives a pose
    library of the reference's faces and vertex order that the repair workflow reads."""
    from posefix.io.meshes import read_mesh
    proc = snakemake(tmp_path, "volumetric_animate", "--config", "volumetric={'animate': {'tet_vertices': 400}}")
    assert proc.returncode == 0, proc.stderr[-3000:]
    library = tmp_path / "data" / "authored" / "demo-limb-markers"
    names = sorted(p.name for p in library.iterdir() if not p.name.startswith("."))
    assert names == [f"demo-limb-markers-{k:04d}.obj" for k in range(13)] + ["demo-limb-markers-reference.obj"]
    V, F = read_mesh(library / "demo-limb-markers-reference.obj")
    last, F_last = read_mesh(library / "demo-limb-markers-0012.obj")
    assert np.array_equal(F, F_last) and np.abs(last - V).max() > 1.0  # the tip went round the bend
    with h5py.File(tmp_path / "results" / "authored" / "demo-limb-markers" / "volumetric_animate.h5", "r") as fh:
        # the surface passes within 5 % d of every marker on 400 tet vertices (0.9 % at the default 2500)
        assert fh["residuals"].shape == (13, 8) and fh["metrics"].attrs["residual_max_rel"] < 0.05
    proc = snakemake(tmp_path, *repair_options("demo-limb-markers"), f"library={library}", "poses=demo-limb-markers-0012")
    assert proc.returncode == 0, proc.stderr[-3000:]
    entry = json.loads((tmp_path / "reports" / "demo-limb-markers" / "summary.json").read_text())["poses"][0]
    assert entry["pose"] == "demo-limb-markers-0012" and entry["intersecting_faces"]["repaired_new"] == 0
