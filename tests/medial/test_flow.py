"""The medial-ball flow (S1 §4): the union-of-balls function, separation of interpenetrating parts, and S1 Fig. 13's
error ordering SSD > variational > variational + flow on a bent ellipsoid."""

import numpy as np
import pytest

from conftest import icosphere
from posefix.mesh.geometry import bbox_diagonal
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.mesh.primitives import capsule
from posefix.medial.authoring import SkeletalPoser, union_error
from posefix.medial.flow import MedialBallFlow, candidate_balls, nearest_balls, union_of_balls
from posefix.medial.reconstruction import SkeletalReconstruction
from posefix.medial.rig import Rig, pose_from_rotation_vectors
from posefix.medial.skeletal_mesh import skeletal_mesh


def test_union_of_two_balls_is_the_smaller_signed_distance():
    f = union_of_balls(np.array([[0.0, 0, 0], [3, 0, 0], [1.5, 2, 0]]), np.array([[0.0, 0, 0], [2, 0, 0]]),
                       np.array([1.0, 0.5]))
    assert np.allclose(f, [-1.0, 0.5, 2.5 - 1.0])


def test_a_foreign_ball_is_reported_inflated_by_the_margin():
    X = np.array([[0.0, 0, 0], [0.5, 0, 0], [5.0, 0, 0]])
    S_d = np.array([[-1.0, 0, 0], [1.5, 0, 0], [6.0, 0, 0]])
    R = np.ones(3)
    clearance = lambda i, j: np.where(i == j, 0.0, 1.0)  # noqa: E731  every other ball was clear at rest
    (g, p), (h, q) = nearest_balls(X, S_d, R, clearance, margin=0.0)
    assert p.tolist() == [0, 1, 2] and np.allclose(g, 0.0) and np.isinf(h).all()  # S1: no foreign balls
    (g, p), (h, q) = nearest_balls(X, S_d, R, clearance, margin=0.1)
    assert p.tolist() == [0, 1, 2] and np.allclose(g, 0.0)
    assert q[:2].tolist() == [1, 0] and np.allclose(h[:2], 0.5 - 0.1) and np.isinf(h[2])  # 2: no neighbour


def test_the_flow_separates_two_interpenetrating_capsules_and_keeps_the_anchors():
    Vc, Fc = capsule(around=24, cap_rings=6, length_rings=30, radius=0.5, length=3.0)
    V, F = np.vstack([Vc, Vc + [0, 2.0, 0]]), np.vstack([Fc, Fc + len(Vc)])
    skeleton = skeletal_mesh(V, F)
    shift = np.zeros_like(V)
    shift[len(Vc):, 1] = -1.1  # axes 0.9 apart: 0.1 of overlap
    X, S_d = V + shift, skeleton.S + shift
    anchors = S_d.copy()
    assert intersecting_faces(self_intersecting_pairs(X, F), len(F)).sum() > 100
    flow = MedialBallFlow(SkeletalReconstruction(V, F, skeleton.S), S_d, margin=0.01 * bbox_diagonal(V))
    result = flow.run(X, max_iters=50)
    assert result.intersecting[0] > 100 and result.intersecting[result.best] == 0
    assert intersecting_faces(self_intersecting_pairs(result.X, F), len(F)).sum() == 0
    assert np.array_equal(S_d, anchors)


def test_a_ball_that_held_a_vertex_at_rest_counts_with_that_penetration_subtracted():
    X, S_d, R = np.array([[0.0, 0, 0], [-0.3, 0, 0]]), np.array([[-1.1, 0, 0], [1.7, 0, 0]]), np.array([1.0, 2.0])
    clearance = lambda i, j: np.where(i == j, 0.0, -0.3)  # noqa: E731  each was 0.3 inside the other's ball
    (g, p), _ = nearest_balls(X, S_d, R, clearance)
    assert p.tolist() == [1, 1] and np.allclose(g, 0.0)  # vertex 0: own ball 0.1, ball 1 -0.3 + 0.3


def test_the_rest_pose_is_a_fixed_point_of_the_flow_despite_overlapping_balls():
    V, F = capsule(around=16, cap_rings=4, length_rings=20)
    skeleton = skeletal_mesh(V, F)  # smoothed: some balls hold neighbouring vertices
    assert union_of_balls(V, skeleton.S, skeleton.R).min() < -1e-4
    result = MedialBallFlow(SkeletalReconstruction(V, F, skeleton.S), skeleton.S, margin=0.01).run(V, max_iters=3)
    assert np.array_equal(result.X, V) and np.allclose(result.error, 0.0)


@pytest.fixture(scope="module")
def bent_ellipsoid():
    """An ellipsoid (2, 1, 0.5) of 5,120 triangles bent by 60 degrees about y at its centre (S1 Fig. 12-13)."""
    V, F = icosphere(4)
    V = V * [2.0, 1.0, 0.5]
    rig = Rig(("root", "mid", "tip"), np.array([[-2.0, 0, 0], [0, 0, 0], [2, 0, 0]]), np.array([-1, 0, 1]))
    poser = SkeletalPoser(V, F, skeletal_mesh(V, F).S, rig)
    pose = pose_from_rotation_vectors(rig, {"mid": [0.0, np.radians(60.0), 0.0]})
    return poser, poser.author(pose, margin=0.0)  # S1's flow


def test_errors_order_ssd_variational_flow_with_s1s_ratios(bent_ellipsoid):
    poser, pose = bent_ellipsoid
    R = poser.reconstruction.R
    ssd, variational, flow = (union_error(pose.positions[v], pose.S_d, R) for v in ("ssd", "variational", "flow"))
    assert ssd > variational > flow
    assert variational / ssd <= 0.3 and flow / variational <= 0.1  # S1 Fig. 13: 3.8 / 20.2 = 0.19, 0.2 / 3.8 = 0.05
    assert pose.flow.intersecting[pose.flow.best] == 0


def test_candidates_are_the_vertices_within_each_radius_or_the_nearest_of_them():
    X = np.column_stack([np.arange(6.0), np.zeros(6), np.zeros(6)])
    R = np.full(6, 1.5)
    j, counts = candidate_balls(X, R, neighbours=0)
    rows = np.split(j, np.cumsum(counts)[:-1])
    assert [sorted(r.tolist()) for r in rows] == [[0, 1], [0, 1, 2], [1, 2, 3], [2, 3, 4], [3, 4, 5], [4, 5]]
    j, counts = candidate_balls(X, R, neighbours=2)
    assert counts.tolist() == [2] * 6 and j[::2].tolist() == list(range(6))  # itself first, then one neighbour
