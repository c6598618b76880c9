"""The medial repair: carried balls, the bent skeleton, the rebuilt damaged region, the stage."""

import h5py
import numpy as np
import pytest

from conftest import run_stage
from posefix.mesh.geometry import bbox_diagonal
from posefix.mesh.rotations import rotation_exp
from posefix.workflow import demo
from posefix.io.meshes import read_mesh, write_mesh
from posefix.medial.flow import MedialBallFlow
from posefix.medial.repair import MedialRepair, medial_repair
from posefix.medial.skeletal_mesh import skeletal_mesh

BENT = demo.DemoPose("bent", ".obj", (0.0, 0.0, 0.0), (0.0, 0.0, np.radians(110.0)), np.radians(30.0))


@pytest.fixture(scope="module")
def limb():
    """A small demo limb, its skeletal mesh and the repair over them."""
    V, F, _ = demo.demo_library(around=20)
    S = skeletal_mesh(V, F).S
    return V, F, S, MedialRepair(V, F, S, margin=0.01 * bbox_diagonal(V))


def test_a_bent_limb_loses_every_new_intersection_and_its_untouched_end_stays(limb):
    V, F, S, repair = limb
    X = demo.pose_limb(V, BENT)  # the last bone folds 110 degrees: its inner side passes through the middle one
    assert repair.new_faces(X).sum() > 20
    result = repair.repair(X)
    assert result.target_faces == repair.new_faces(X).sum()
    assert repair.new_faces(result.X).sum() == 0
    assert result.flow.intersecting[result.flow.best] == 0
    untouched = V[:, 0] < -1.5  # beyond the first joint (x = -1) from the bent one (x = +1)
    assert np.abs(result.X - X)[untouched].max() <= 1e-3 * bbox_diagonal(V)
    assert not result.free[untouched].any() and result.free[np.unique(F[repair.new_faces(X)])].all()


def test_the_deformed_skeleton_of_the_reference_is_its_skeleton(limb):
    V, F, S, repair = limb
    S_d, Q = repair.skeleton(V, repair.rotations(V), np.zeros(len(V), dtype=bool))
    assert np.abs(S_d - S).max() <= 1e-12 * bbox_diagonal(V)
    assert np.abs(Q - np.eye(3)).max() <= 1e-12


def test_the_reference_itself_comes_back_unchanged(limb):
    V, F, S, repair = limb
    result = repair.repair(V.copy())
    assert np.array_equal(result.X, V) and result.reach == 0 and not result.free.any()
    assert result.flow.iterations == 0 and result.target_faces == result.start_faces == 0


def test_a_rigid_motion_carries_the_balls_rigidly_even_through_a_rebuilt_region(limb):
    V, F, S, repair = limb
    Q = rotation_exp(np.array([[0.3, -1.1, 0.7]]))[0]
    X = V @ Q.T + np.array([2.0, -1.0, 0.5])
    free = np.abs(V[:, 0] - 1.0) < 0.6  # a band around the second joint, rebuilt from the rotations around it
    S_d, Q_d = repair.skeleton(X, repair.rotations(X), free)
    d = bbox_diagonal(V)
    assert np.abs(Q_d - Q).max() <= 1e-9
    assert np.abs(S_d - (S @ Q.T + np.array([2.0, -1.0, 0.5]))).max() <= 1e-9 * d
    assert np.abs(repair.rebuild(X, free, Q_d) - X).max() <= 1e-9 * d


def test_the_damaged_region_grows_with_the_reach_and_stays_within_it(limb):
    V, F, S, repair = limb
    faces = repair.new_faces(demo.pose_limb(V, BENT))
    seeds = np.unique(F[faces])
    regions = [repair.damaged(faces, r) for r in (1, 2, 3)]
    for r, free in zip((1, 2, 3), regions):
        assert free[seeds].all()
        # graph distance >= Euclidean distance: nothing farther than r radii (of the largest seed ball)
        far = np.linalg.norm(V[:, None] - V[None, seeds], axis=2).min(axis=1) > r * repair.R[seeds].max()
        assert not free[far].any()
    assert regions[0].sum() < regions[1].sum() < regions[2].sum()
    assert np.all(regions[0] <= regions[1]) and np.all(regions[1] <= regions[2])


def test_the_flow_stops_at_its_first_clean_iterate_when_asked(limb):
    V, F, S, repair = limb
    flow = MedialBallFlow(repair.rec, S, margin=0.0).run(V, max_iters=5, ftol=None)
    assert flow.iterations == 0 and flow.intersecting.tolist() == [0]


def test_the_one_off_function_is_the_class(limb):
    V, F, S, repair = limb
    X = demo.pose_limb(V, BENT)
    a, b = medial_repair(V, F, S, X, margin=0.01 * bbox_diagonal(V)), repair.repair(X)
    assert np.array_equal(a.X, b.X) and a.reach == b.reach


def test_the_stages_repair_a_demo_pose_and_refuse_a_foreign_one(tmp_path):
    V, F, _ = demo.demo_library(around=16)
    write_mesh(tmp_path / "ref.obj", V, F)
    write_mesh(tmp_path / "bent.obj", demo.pose_limb(V, BENT), F)
    run_stage("skeleton", "--reference", tmp_path / "ref.obj", "--out", tmp_path / "skeleton.h5")
    run_stage("repair_medial", "--reference", tmp_path / "ref.obj", "--target", tmp_path / "bent.obj",
              "--skeleton", tmp_path / "skeleton.h5", "--out", tmp_path / "medial.h5")
    with h5py.File(tmp_path / "medial.h5", "r") as fh:
        metrics = fh["metrics"].attrs
        assert fh.attrs["stage"] == "repair_medial" and metrics["intersecting_faces_repaired_new"] == 0
        assert metrics["intersecting_faces_target"] > 0 and fh["intersecting"][0] == metrics["intersecting_faces_start"]
        assert "start" not in fh  # the target: the summary reads it from keyframes.h5
        X = fh["repaired"][()]
    run_stage("export", "--artifact", tmp_path / "medial.h5", "--stage", "repair_medial",
              "--reference", tmp_path / "ref.obj", "--target", tmp_path / "bent.obj", "--out", tmp_path / "out.obj")
    V_out, F_out = read_mesh(tmp_path / "out.obj")
    assert np.array_equal(V_out, X) and np.array_equal(F_out, F)
    write_mesh(tmp_path / "other.obj", V[:-1], F[:10])
    proc = run_stage("repair_medial", "--reference", tmp_path / "ref.obj", "--target", tmp_path / "other.obj",
                     "--skeleton", tmp_path / "skeleton.h5", "--out", tmp_path / "bad.h5", check=False)
    assert proc.returncode == 2 and "other.obj" in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "bad.h5").exists()
