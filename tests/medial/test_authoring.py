"""Pose authoring through the skeletal mesh: the rest pose is the identity, a rigid rig motion is rigid."""

import numpy as np
import pytest

from posefix.mesh.geometry import bbox_diagonal
from posefix.mesh.rotations import rotation_exp
from posefix.workflow import demo
from posefix.medial.authoring import VARIANTS, SkeletalPoser, union_error
from posefix.medial.rig import Rig, RigPose
from posefix.medial.skeletal_mesh import skeletal_mesh

LIMB = Rig(("root", "j1", "j2", "tip"), np.array([[-3.0, 0, 0], [-1, 0, 0], [1, 0, 0], [3, 0, 0]]),
           np.array([-1, 0, 1, 2]))


@pytest.fixture(scope="module")
def poser():
    V, F, _ = demo.demo_library(around=16)
    return SkeletalPoser(V, F, skeletal_mesh(V, F).S, LIMB)


def test_the_rest_pose_gives_the_mesh_back(poser):
    rest = RigPose(np.repeat(np.eye(3)[None], 4, axis=0))
    authored = poser.author(rest, margin=0.0, max_iters=3)
    assert list(authored.positions) == list(VARIANTS)
    d = bbox_diagonal(poser.V)
    for variant in VARIANTS:
        assert np.abs(authored.positions[variant] - poser.V).max() <= 1e-9 * d, variant
    assert np.abs(authored.S_d - poser.S).max() <= 1e-12 * d


def test_a_rigid_motion_of_every_bone_moves_every_variant_rigidly(poser):
    Q = rotation_exp(np.array([[0.2, 1.3, -0.4]]))[0]
    t = np.array([3.0, -1.0, 0.5])
    pose = RigPose(np.concatenate([Q[None], np.repeat(np.eye(3)[None], 3, axis=0)]), t)
    moved = (poser.V - LIMB.rest[0]) @ Q.T + LIMB.rest[0] + t
    d = bbox_diagonal(poser.V)
    authored = poser.author(pose, margin=0.01 * d, max_iters=3)
    for variant in VARIANTS:
        assert np.abs(authored.positions[variant] - moved).max() <= 1e-9 * d, variant


def test_union_error_sums_the_distances_to_the_union_of_balls():
    P, centres = np.array([[1.0, 0, 0], [6, 0, 0], [2, 0, 0], [5, 0, 0]]), np.array([[0.0, 0, 0], [5, 0, 0]])
    assert union_error(P, centres, np.ones(2)) == 0 + 0 + 1 + 1
