"""The pass-through fallback (S0 Fig. 9): regions the flow could not bring to the target come from it."""

import numpy as np
import trimesh

from conftest import icosphere
from posefix.mesh.geometry import bbox_diagonal
from posefix.mesh.intersections import self_intersecting_pairs
from posefix.mesh.primitives import capsule
from posefix.verify.fallback import fallback, pass_through_regions, transient_pairs
from posefix.verify.flags import REPLACED_NEW_INTERSECTION, REPLACED_PASS_THROUGH
from posefix.verify.sequence import RepairSettings
from posefix.verify.state import RepairProblem
from posefix.spacetime.classification import constraint_mask
from posefix.spacetime.constraints import spacetime_constraints
from posefix.spacetime.fit import FitSettings, iterate, start_fit
from posefix.spacetime.integration import field_velocity, rk45
from posefix.spacetime.keyframes import keyframes


def test_transient_pairs_are_the_ones_of_intermediate_frames_only():
    a, b, c = np.array([[1, 2]]), np.array([[1, 2], [3, 4]]), np.array([[5, 6]])
    assert transient_pairs([a, b, c, c]).tolist() == [[3, 4]]


def _rod_through_ball():
    """Key frames that move a rod straight through a ball: V_ref, V_tgt, F, frames, t, first rod vertex."""
    ball = trimesh.creation.icosphere(subdivisions=3)
    Vc, Fc = capsule(around=12, cap_rings=3, length_rings=24, radius=0.15, length=5.0)
    Vc = Vc[:, [1, 2, 0]]
    nb = len(ball.vertices)
    F = np.vstack([ball.faces, Fc + nb])
    V_ref = np.vstack([ball.vertices, Vc - [2.5, 0, 0]])
    V_tgt = np.vstack([ball.vertices, Vc + [2.5, 0, 0]])
    frames, t, _ = keyframes(V_ref, V_tgt, F, 11, align=False)
    return V_ref, V_tgt, F, frames, t, nb


def test_rod_passing_through_a_ball_falls_back_to_the_target():
    # the flow cannot pass the rod through the ball and leaves its middle behind: that part must come
    # from the target (S0 Fig. 9)
    V_ref, V_tgt, F, frames, t, nb = _rod_through_ball()
    frame_pairs = [self_intersecting_pairs(x, F) for x in frames]
    assert len(frame_pairs[0]) == len(frame_pairs[-1]) == 0 and max(len(p) for p in frame_pairs) > 0
    mask, _ = constraint_mask(F, len(V_ref), frame_pairs, ring=1)
    d = bbox_diagonal(V_ref)
    Y, V, _, _ = spacetime_constraints(frames, t, mask, 12, tau=0.3 * d, tangents="hermite")
    fit = start_fit(Y, V, FitSettings(eps=1e-4 * d, max_centers=1000, batch=64))
    iterate(fit)
    X, _, _, _ = rk45(field_velocity(fit.field(), 0.3 * d), V_ref, atol=1e-7 * d, rtol=1e-9)
    assert np.abs(X[nb:] - V_tgt[nb:]).max() > 0.1 * d  # left behind
    problem = RepairProblem.build(V_ref, V_tgt, F, mask, frame_pairs)
    X2, replaced, new = fallback(problem, X, 0.01 * d, RepairSettings())
    assert (replaced[nb:] & REPLACED_PASS_THROUGH).any() and not new.any()
    assert np.abs(X2[nb:] - V_tgt[nb:]).max() < 0.01 * d


def test_pass_through_regions_close_over_the_unconstrained_parts_they_touch():
    """A far constrained vertex seeds a region that takes in the whole unconstrained part next to it."""
    V, F = icosphere(2)
    mask = V[:, 0] < 0.5  # the cap x >= 0.5 is unconstrained
    far = np.zeros(len(V), dtype=bool)
    seed = int(np.flatnonzero(mask)[np.argmax(V[mask, 0])])  # constrained, next to the cap
    far[seed] = True
    empty = np.zeros((0, 2), dtype=np.int64)
    regions = pass_through_regions(RepairProblem.build(V, V, F, mask, [empty, empty]), far, ring=0)
    assert len(regions) == 1 and seed in regions[0] and set(np.flatnonzero(~mask)) <= set(regions[0])
    assert pass_through_regions(RepairProblem.build(V, V, F, mask, [empty, empty]), far & False, ring=0) == []


def test_near_contact_pushed_through_is_untangled_by_the_target():
    V1, F1 = icosphere(3)
    V2, F2 = icosphere(3, centre=(2.01, 0.0, 0.0))  # 0.01 apart in the target
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    X = V.copy()
    bump = (X[:, 0] > 0.9) & (np.arange(len(V)) < len(V1))
    X[bump, 0] += 0.05  # the integrated pose pushes one sphere into the other
    empty = np.zeros((0, 2), dtype=np.int64)
    problem = RepairProblem.build(V, V, F, np.ones(len(V), bool), [empty, empty])
    X2, replaced, new = fallback(problem, X, 1.0, RepairSettings())
    assert len(self_intersecting_pairs(X, F)) > 0 and not new.any()
    assert (replaced[bump] & REPLACED_NEW_INTERSECTION).all()
    assert np.array_equal(X2, V)
    _, untouched, left = fallback(problem, X, 1.0, RepairSettings(repair_new=False))
    assert not untouched.any() and left.any()  # repair_new off: nothing is untangled
