"""Rig: skinning weights, joint transforms and linear blend skinning, against the demo limb's own skinning."""

import numpy as np

from conftest import ROOT
from posefix.mesh.rotations import rotation_exp
from posefix.workflow import demo
from posefix.medial.rig_files import read_rig
from posefix.medial.rig import (Rig, RigPose, blend_skin, blended_linear_maps, bone_distances, bone_transforms,
                                  pose_from_rotation_vectors, skinning_weights)

LIMB = Rig(("root", "j1", "j2", "tip"), np.array([[-3.0, 0, 0], [-1, 0, 0], [1, 0, 0], [3, 0, 0]]),
           np.array([-1, 0, 1, 2]))


def test_bone_distances_of_points_beside_and_beyond_a_segment():
    d = bone_distances(LIMB, np.array([[0.0, 0.5, 0.0], [4.0, 0.0, 0.0]]))
    assert np.allclose(d[0], [np.hypot(1.0, 0.5), 0.5, np.hypot(1.0, 0.5)])
    assert np.allclose(d[1], [5.0, 3.0, 1.0])


def test_weights_are_a_partition_of_unity_one_hot_mid_bone_and_half_at_a_joint():
    P = np.array([[0.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    w = skinning_weights(LIMB, P)
    assert np.allclose(w.sum(1), 1.0) and (w >= 0).all()
    assert w[0, 1] > 0.99 and np.allclose(w[1, :2], 0.5) and w[2, 2] > 0.99  # exp(-(1 / 0.4)^2) per other bone


def test_the_demo_rig_file_reproduces_the_demo_poses_with_the_demo_weights():
    V, F, poses = demo.demo_library(around=12)
    rig, rig_poses = read_rig(ROOT / "examples" / "demo-limb.yaml")
    assert list(rig_poses) == [p.name for p in demo.POSES]
    weights = demo.skinning_weights(V[:, 0])
    for name, pose in rig_poses.items():
        assert np.abs(blend_skin(V, weights, *bone_transforms(rig, pose)) - poses[name]).max() < 1e-12


def test_a_rotated_and_translated_root_moves_everything_rigidly():
    Q = rotation_exp(np.array([[0.3, -0.2, 0.9]]))[0]
    pose = RigPose(np.concatenate([Q[None], np.repeat(np.eye(3)[None], 3, 0)]), np.array([1.0, 2.0, 3.0]))
    P = np.random.default_rng(0).normal(size=(20, 3))
    A, t = bone_transforms(LIMB, pose)
    w = skinning_weights(LIMB, P)
    moved = Q @ (P - LIMB.rest[0]).T
    assert np.allclose(blend_skin(P, w, A, t), moved.T + LIMB.rest[0] + [1.0, 2.0, 3.0])
    assert np.allclose(blended_linear_maps(w, A), Q)


def test_a_joint_rotation_moves_only_the_bones_below_it():
    pose = pose_from_rotation_vectors(LIMB, {"j2": [0.0, 0.0, np.pi / 2]})
    A, t = bone_transforms(LIMB, pose)
    assert np.allclose(A[:2], np.eye(3)) and np.allclose(A[2] @ [3.0, 0, 0] + t[2], [1.0, 2.0, 0.0])
