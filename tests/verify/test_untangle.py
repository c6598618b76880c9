"""Untangling new intersections: separation along the reference's axes, smoothing, the rigid reference."""

import numpy as np

from conftest import grid_sheet, icosphere
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.mesh.topology import vertex_adjacency
from posefix.verify.flags import RIGID_REFERENCE, SEPARATED, SMOOTHED
from posefix.verify.state import RepairProblem, RepairState
from posefix.verify.untangle import smooth, untangle


def _untangled(V_ref, X, F, mask, frame_pairs, max_rings=6):
    """Untangle ``X`` (target = ``X``) with 1 to ``max_rings`` rings: (positions, flags, new faces)."""
    problem = RepairProblem.build(V_ref, X, F, mask, frame_pairs)
    state = RepairState(X, F, problem.reference_faces)
    untangle(problem, state, 1, max_rings)
    return state.X, state.replaced, state.new


def test_spike_of_a_free_region_is_smoothed_out():
    # two parallel sheets; the repaired pose (and the target) push one vertex of the upper
    # sheet's unconstrained middle through the lower sheet: smoothing the free vertices fixes it
    n = 21
    V1, F1 = grid_sheet(n, 0.0)
    V2, F2 = grid_sheet(n, 0.1)
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    tip = len(V1) + (n // 2) * n + n // 2
    X = V.copy()
    X[tip, 2] = -0.1
    assert len(self_intersecting_pairs(X, F)) > 0
    mask = np.ones(len(V), dtype=bool)
    mask[len(V1):] = np.linalg.norm(V2[:, :2] - 0.5, axis=1) > 0.2
    empty = np.zeros((0, 2), dtype=np.int64)
    X2, replaced, new = _untangled(V, X, F, mask, [empty, self_intersecting_pairs(X, F)])
    assert not new.any() and replaced[tip] & SMOOTHED
    assert not (replaced & ~np.uint8(SMOOTHED)).any()  # the target (same spike) was tried and rejected
    assert np.array_equal(X2[mask], X[mask])  # constrained vertices untouched
    assert X2[tip, 2] > 0.0


def _inflated_pair_of_spheres(scale):
    """Two unit icospheres that intersect in the reference, the second inflated by ``scale`` in the repaired
    pose (the rim of the reference's intersection moves over new faces): V_ref, X, F, frame pairs."""
    V1, F1 = icosphere(3)
    V2, F2 = icosphere(3, centre=(1.6, 0.0, 0.0))  # the reference already intersects
    V_ref, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    X = V_ref.copy()
    X[len(V1):] = (V_ref[len(V1):] - [1.6, 0, 0]) * scale + [1.6, 0, 0]
    ref_pairs = self_intersecting_pairs(V_ref, F)
    assert (intersecting_faces(self_intersecting_pairs(X, F), len(F)) & ~intersecting_faces(ref_pairs, len(F))).any()
    return V_ref, X, F, [ref_pairs, self_intersecting_pairs(X, F)]


def test_rim_of_a_reference_intersection_moved_apart_along_the_reference_axes():
    """A rim that crept a little over new faces: only the vertices of the new pairs move, by less than an
    edge, apart along the axes that separate them in the reference."""
    V_ref, X, F, frame_pairs = _inflated_pair_of_spheres(1.04)
    X2, replaced, new = _untangled(V_ref, X, F, np.ones(len(X), bool), frame_pairs)
    assert not new.any() and (replaced == SEPARATED).sum() > 0 and not (replaced & ~np.uint8(SEPARATED)).any()
    moved = (X2 != X).any(axis=1)
    assert np.array_equal(moved, replaced > 0)
    edge = np.linalg.norm(X[F[:, 1]] - X[F[:, 0]], axis=1).mean()
    assert np.linalg.norm(X2 - X, axis=1).max() < edge


def test_rim_of_a_reference_intersection_restored_rigidly():
    """A rim moved too far for small moves (over an edge): the reference's shape moved rigidly onto the region."""
    V_ref, X, F, frame_pairs = _inflated_pair_of_spheres(1.2)
    X2, replaced, new = _untangled(V_ref, X, F, np.ones(len(X), bool), frame_pairs)
    assert not new.any() and (replaced & RIGID_REFERENCE).any()


def test_smoothing_is_jacobi_towards_the_neighbours_mean_with_the_rest_fixed():
    V, F = grid_sheet(3, 0.0)
    X = V.copy()
    X[4, 2] = 1.0  # the middle vertex of a 3 x 3 grid, six neighbours at z = 0
    A = vertex_adjacency(F, len(V))
    Y = smooth(X, A, np.array([4]), 1)
    assert Y[4, 2] == 0.5 and np.array_equal(np.delete(Y, 4, axis=0), np.delete(X, 4, axis=0))
    assert smooth(X, A, np.array([4]), 3)[4, 2] == 0.125
