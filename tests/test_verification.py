"""Verification and fallback: deviation summary, pass-through (S0 Fig. 9), untangling new intersections."""

import numpy as np
import trimesh

from conftest import icosphere
from posefix.classification import constraint_mask
from posefix.constraints import spacetime_constraints
from posefix.fit import FitSettings, iterate, start_fit
from posefix.geometry import bbox_diagonal
from posefix.harmonic import harmonic_extension
from posefix.integration import field_velocity, rk45
from posefix.intersections import intersecting_faces, self_intersecting_pairs
from posefix.keyframes import keyframes
from posefix.synth import capsule
from posefix.topology import vertex_adjacency
from posefix.verification import (PUSHED, REPLACED_NEW_INTERSECTION, REPLACED_PASS_THROUGH, RIGID_REFERENCE,
                                  SEPARATED, SMOOTHED, deviation, fallback, reproduce_targets, transient_pairs)


def _pairs(V, F):
    return self_intersecting_pairs(V, F)


def test_deviation_summary():
    X = np.zeros((4, 3))
    V = np.array([[0.0, 0, 0], [3.0, 0, 0], [0, 4.0, 0], [0, 0, 1.0]])
    dev, s = deviation(X, V, np.array([True, True, False, False]), d=2.0)
    assert np.allclose(dev, [0, 1.5, 2.0, 0.5])
    assert s["constrained_max"] == 1.5 and s["constrained_mean"] == 0.75 and s["free_max"] == 2.0


def test_transient_pairs_are_the_ones_of_intermediate_frames_only():
    a, b, c = np.array([[1, 2]]), np.array([[1, 2], [3, 4]]), np.array([[5, 6]])
    assert transient_pairs([a, b, c, c]).tolist() == [[3, 4]]


def test_rod_passing_through_a_ball_falls_back_to_the_target():
    # key frames move a rod straight through a ball; the flow cannot, and leaves the rod's middle
    # behind: that part must come from the target (S0 Fig. 9)
    ball = trimesh.creation.icosphere(subdivisions=3)
    Vc, Fc = capsule(around=12, cap_rings=3, length_rings=24, radius=0.15, length=5.0)
    Vc = Vc[:, [1, 2, 0]]
    nb = len(ball.vertices)
    F = np.vstack([ball.faces, Fc + nb])
    V_ref = np.vstack([ball.vertices, Vc - [2.5, 0, 0]])
    V_tgt = np.vstack([ball.vertices, Vc + [2.5, 0, 0]])
    frames, t, _ = keyframes(V_ref, V_tgt, F, 11, align=False)
    frame_pairs = [_pairs(x, F) for x in frames]
    assert len(frame_pairs[0]) == len(frame_pairs[-1]) == 0 and max(len(p) for p in frame_pairs) > 0
    mask, _ = constraint_mask(F, len(V_ref), frame_pairs, ring=1)
    d = bbox_diagonal(V_ref)
    Y, V, _, _ = spacetime_constraints(frames, t, mask, 12, 0.3 * d)
    fit = start_fit(Y, V, FitSettings(eps=1e-4 * d, max_centers=1000, batch=64))
    iterate(fit)
    X, _, _, _ = rk45(field_velocity(fit.field(), 0.3 * d), V_ref, 1e-9, 1e-7 * d)
    assert np.abs(X[nb:] - V_tgt[nb:]).max() > 0.1 * d  # left behind
    X2, replaced, new = fallback(X, V_ref, V_tgt, F, mask, frame_pairs, 0.01 * d)
    assert (replaced[nb:] & REPLACED_PASS_THROUGH).any() and not new.any()
    assert np.abs(X2[nb:] - V_tgt[nb:]).max() < 0.01 * d


def test_near_contact_pushed_through_is_untangled_by_the_target():
    V1, F1 = icosphere(3)
    V2, F2 = icosphere(3, centre=(2.01, 0.0, 0.0))  # 0.01 apart in the target
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    X = V.copy()
    bump = (X[:, 0] > 0.9) & (np.arange(len(V)) < len(V1))
    X[bump, 0] += 0.05  # the integrated pose pushes one sphere into the other
    empty = np.zeros((0, 2), dtype=np.int64)
    X2, replaced, new = fallback(X, V, V, F, np.ones(len(V), bool), [empty, empty], threshold=1.0)
    assert len(_pairs(X, F)) > 0 and not new.any()
    assert (replaced[bump] & REPLACED_NEW_INTERSECTION).all()
    assert np.array_equal(X2, V)


def _grid(n, z):
    """An n x n unit grid at height z: (n*n, 3) float vertices and (2(n-1)^2, 3) int faces."""
    g = np.linspace(0, 1, n)
    V = np.column_stack([np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2), np.full(n * n, z)])
    F = [[i * n + j, (i + 1) * n + j, (i + 1) * n + j + 1] for i in range(n - 1) for j in range(n - 1)]
    F += [[i * n + j, (i + 1) * n + j + 1, i * n + j + 1] for i in range(n - 1) for j in range(n - 1)]
    return V, np.array(F)


def test_spike_of_a_free_region_is_smoothed_out():
    # two parallel sheets; the repaired pose (and the target) push one vertex of the upper
    # sheet's unconstrained middle through the lower sheet: smoothing the free vertices fixes it
    n = 21
    V1, F1 = _grid(n, 0.0)
    V2, F2 = _grid(n, 0.1)
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    tip = len(V1) + (n // 2) * n + n // 2
    X = V.copy()
    X[tip, 2] = -0.1
    assert len(_pairs(X, F)) > 0
    mask = np.ones(len(V), dtype=bool)
    mask[len(V1):] = np.linalg.norm(V2[:, :2] - 0.5, axis=1) > 0.2
    empty = np.zeros((0, 2), dtype=np.int64)
    X2, replaced, new = fallback(X, V, X, F, mask, [empty, _pairs(X, F)], threshold=10.0)
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
    ref_pairs = _pairs(V_ref, F)
    assert (intersecting_faces(_pairs(X, F), len(F)) & ~intersecting_faces(ref_pairs, len(F))).any()
    return V_ref, X, F, [ref_pairs, _pairs(X, F)]


def test_rim_of_a_reference_intersection_moved_apart_along_the_reference_axes():
    """A rim that crept a little over new faces: only the vertices of the new pairs move, by less than an
    edge, apart along the axes that separate them in the reference."""
    V_ref, X, F, frame_pairs = _inflated_pair_of_spheres(1.04)
    X2, replaced, new = fallback(X, V_ref, X, F, np.ones(len(X), bool), frame_pairs, threshold=10.0)
    assert not new.any() and (replaced == SEPARATED).sum() > 0 and not (replaced & ~np.uint8(SEPARATED)).any()
    moved = (X2 != X).any(axis=1)
    assert np.array_equal(moved, replaced > 0)
    edge = np.linalg.norm(X[F[:, 1]] - X[F[:, 0]], axis=1).mean()
    assert np.linalg.norm(X2 - X, axis=1).max() < edge


def test_rim_of_a_reference_intersection_restored_rigidly():
    """A rim moved too far for small moves (over an edge): the reference's shape moved rigidly onto the region."""
    V_ref, X, F, frame_pairs = _inflated_pair_of_spheres(1.2)
    X2, replaced, new = fallback(X, V_ref, X, F, np.ones(len(X), bool), frame_pairs, threshold=10.0, max_rings=6)
    assert not new.any() and (replaced & RIGID_REFERENCE).any()


def _sheet_over_patch():
    """A patch (z = 0, xy in [0.4, 0.6]^2) under a sheet (z = 0.05); V (n, 3), F (m, 3), first sheet index."""
    V1, F1 = _grid(21, 0.05)
    V2, F2 = _grid(5, 0.0)
    V2[:, :2] = 0.4 + 0.2 * V2[:, :2]
    return np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)]), len(V1)


def test_reproduction_puts_constrained_vertices_on_their_targets():
    V, F, ns = _sheet_over_patch()
    X = V + [1e-3, -2e-3, 5e-4]  # a smooth (here constant) residual of the fit
    keep = np.ones(len(V), dtype=bool)
    keep[:ns] = np.abs(V[:ns, 0] - 0.5) > 0.2  # the sheet's middle band is free
    none = np.zeros(len(F), dtype=bool)
    Y, moved, _ = reproduce_targets(X, V, F, vertex_adjacency(F, len(V)), keep, np.zeros(len(V), bool), none)
    assert np.array_equal(Y[keep], V[keep]) and moved.all()
    assert np.abs(Y - V).max() < 1e-12  # the blend carries a constant residual exactly
    assert len(_pairs(Y, F)) == 0


def test_reproduction_holds_back_where_it_would_add_intersections():
    V, F, ns = _sheet_over_patch()
    keep = np.zeros(len(V), dtype=bool)
    keep[:ns] = np.abs(V[:ns, 0] - 0.5) > 0.2
    tgt = V.copy()
    tgt[:ns][V[:ns, 0] < 0.3, 2] = -0.05  # the left band's target is below the patch: the ramp would cut it
    A = vertex_adjacency(F, len(V))
    none = np.zeros(len(F), dtype=bool)
    hold = np.zeros(len(V), dtype=bool)
    assert len(_pairs(V, F)) == 0
    ramp = V + harmonic_extension(A, np.where(keep[:, None], tgt - V, 0.0), keep)
    assert len(_pairs(ramp, F)) > 0  # a plain blend would add intersections
    Y, moved, _ = reproduce_targets(V, tgt, F, A, keep, hold, none)
    assert len(_pairs(Y, F)) == 0
    on_target = (Y == tgt).all(axis=1) & keep
    assert on_target.sum() > 0.5 * keep.sum() and moved.any()


def test_reproduction_moves_held_back_parts_as_far_as_they_can_go():
    """A dent of the sheet's target reaches through the patch below: the dent goes down as far as it
    can without touching the patch (the largest fraction found by bisection), the rest is exact."""
    V, F, ns = _sheet_over_patch()
    keep, hold = np.zeros(len(V), dtype=bool), np.zeros(len(V), dtype=bool)
    keep[:ns], hold[ns:] = True, True
    tgt = V.copy()
    dent = np.flatnonzero(np.linalg.norm(V[:ns, :2] - 0.5, axis=1) < 0.06)
    tgt[dent, 2] -= 0.08  # target z = -0.03: through the patch at z = 0
    none = np.zeros(len(F), dtype=bool)
    Y, moved, _ = reproduce_targets(V, tgt, F, vertex_adjacency(F, len(V)), keep, hold, none)
    assert len(_pairs(Y, F)) == 0 and np.array_equal(Y[ns:], V[ns:])
    assert (Y[dent, 2] > 0).all() and (Y[dent, 2] < 0.05 - 0.04).all()  # at least half way down
    far = np.linalg.norm(V[:ns, :2] - 0.5, axis=1) > 0.3
    assert np.array_equal(Y[:ns][far], tgt[:ns][far])


def test_reproduction_pushes_an_unconstrained_patch_out_of_the_way():
    """The sheet's target has a dent through a free patch below it: the dent goes all the way (bitwise on
    target) and the patch is pushed down under it, smoothly and by about the dent's depth, not held back."""
    V, F, ns = _sheet_over_patch()
    keep = np.zeros(len(V), dtype=bool)
    keep[:ns] = True
    tgt = V.copy()
    dent = np.flatnonzero(np.linalg.norm(V[:ns, :2] - 0.5, axis=1) < 0.06)
    tgt[dent, 2] -= 0.08  # target z = -0.03: through the patch at z = 0
    none = np.zeros(len(F), dtype=bool)
    Y, moved, pushed = reproduce_targets(V, tgt, F, vertex_adjacency(F, len(V)), keep, np.zeros(len(V), bool), none)
    assert len(_pairs(Y, F)) == 0 and np.array_equal(Y[:ns], tgt[:ns])
    assert pushed.any() and not pushed[:ns].any() and moved[pushed].all()
    assert (Y[ns:, 2] <= 0.0).all() and Y[ns:, 2].min() > -0.03 - 0.1  # down, about as deep as the dent
    assert np.abs(Y[ns:, :2] - V[ns:, :2]).max() < 0.02  # pushed along the separating axis (z)
