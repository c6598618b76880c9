"""The built-in demo library: clean reference, every target self-intersects, deterministic files."""

import numpy as np

from conftest import run_stage
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.mesh.topology import edges, half_edges
from posefix.workflow import demo as synth
from posefix.io.library import discover_library
from posefix.io.meshes import read_mesh


def test_reference_is_a_clean_closed_limb(demo):
    V, F, _ = demo
    assert 2000 <= len(V) <= 5000
    assert len(self_intersecting_pairs(V, F)) == 0
    _, counts = np.unique(half_edges(F), axis=0, return_counts=True)
    assert (counts == 2).all()  # closed 2-manifold
    assert len(V) - len(edges(F)) + len(F) == 2  # sphere topology


def test_every_target_self_intersects_at_the_inner_side_of_a_joint(demo):
    V_ref, F, poses = demo
    assert len(poses) >= 3
    for name, V in poses.items():
        faces = intersecting_faces(self_intersecting_pairs(V, F), len(F))
        assert faces.sum() >= 50, name
        # intersections sit within four limb radii of a joint (x = -1 or +1) along the reference
        x = V_ref[F[faces]].mean(axis=1)[:, 0]
        near_joint = np.min(np.abs(x[:, None] - np.array(synth.JOINTS)[None]), axis=1) < 4 * synth.RADIUS
        assert near_joint.all(), name


def test_demo_stage_is_deterministic_and_readable(tmp_path):
    for out in ("a", "b"):
        run_stage("demo", "--out", tmp_path / out, "--seed", 3)
    files = sorted(p.name for p in (tmp_path / "a").iterdir())
    assert len(files) == 1 + len(synth.POSES)
    for name in files:
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    lib = discover_library(tmp_path / "a")
    assert lib.reference.name == "demo-reference" and len(lib.poses) == len(synth.POSES)
    V_ref, F, poses = synth.demo_library(seed=3)
    for pose in lib.poses:
        V, F2 = read_mesh(pose.path)
        assert np.array_equal(F2, F) and np.array_equal(V, poses[pose.name])
