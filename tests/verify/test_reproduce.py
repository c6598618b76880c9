"""Reproduction of V_C: snap onto the target, blend the residual, push free parts out, hold back the rest."""

import numpy as np

from conftest import grid_sheet
from posefix.mesh.harmonic import harmonic_extension
from posefix.mesh.intersections import self_intersecting_pairs
from posefix.verify.reproduce import reproduce_targets
from posefix.verify.state import RepairProblem


def _sheet_over_patch():
    """A patch (z = 0, xy in [0.4, 0.6]^2) under a sheet (z = 0.05); V (n, 3), F (m, 3), first patch index."""
    V1, F1 = grid_sheet(21, 0.05)
    V2, F2 = grid_sheet(5, 0.0)
    V2[:, :2] = 0.4 + 0.2 * V2[:, :2]
    return np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)]), len(V1)


def _problem(V_tgt, F):
    """Targets ``V_tgt``, a clean reference."""
    empty = np.zeros((0, 2), dtype=np.int64)
    return RepairProblem.build(V_tgt, V_tgt, F, np.ones(len(V_tgt), bool), [empty, empty])


def _dent(V, ns):
    """The sheet's target with a dent down to z = -0.03, through the patch at z = 0: (target, dent vertices)."""
    tgt = V.copy()
    dent = np.flatnonzero(np.linalg.norm(V[:ns, :2] - 0.5, axis=1) < 0.06)
    tgt[dent, 2] -= 0.08
    return tgt, dent


def test_reproduction_puts_constrained_vertices_on_their_targets():
    V, F, ns = _sheet_over_patch()
    X = V + [1e-3, -2e-3, 5e-4]  # a smooth (here constant) residual of the fit
    keep = np.ones(len(V), dtype=bool)
    keep[:ns] = np.abs(V[:ns, 0] - 0.5) > 0.2  # the sheet's middle band is free
    Y, moved, _ = reproduce_targets(_problem(V, F), X, keep, np.zeros(len(V), bool))
    assert np.array_equal(Y[keep], V[keep]) and moved.all()
    assert np.abs(Y - V).max() < 1e-12  # the blend carries a constant residual exactly
    assert len(self_intersecting_pairs(Y, F)) == 0


def test_reproduction_holds_back_where_it_would_add_intersections():
    V, F, ns = _sheet_over_patch()
    keep = np.zeros(len(V), dtype=bool)
    keep[:ns] = np.abs(V[:ns, 0] - 0.5) > 0.2
    tgt = V.copy()
    tgt[:ns][V[:ns, 0] < 0.3, 2] = -0.05  # the left band's target is below the patch: the ramp would cut it
    problem = _problem(tgt, F)
    assert len(self_intersecting_pairs(V, F)) == 0
    ramp = V + harmonic_extension(problem.A, np.where(keep[:, None], tgt - V, 0.0), keep)
    assert len(self_intersecting_pairs(ramp, F)) > 0  # a plain blend would add intersections
    Y, moved, _ = reproduce_targets(problem, V, keep, np.zeros(len(V), dtype=bool))
    assert len(self_intersecting_pairs(Y, F)) == 0
    on_target = (Y == tgt).all(axis=1) & keep
    assert on_target.sum() > 0.5 * keep.sum() and moved.any()


def test_reproduction_moves_held_back_parts_as_far_as_they_can_go():
    """A dent of the sheet's target reaches through the patch below: the dent goes down as far as it
    can without touching the patch (the largest fraction found by bisection), the rest is exact."""
    V, F, ns = _sheet_over_patch()
    keep, hold = np.zeros(len(V), dtype=bool), np.zeros(len(V), dtype=bool)
    keep[:ns], hold[ns:] = True, True
    tgt, dent = _dent(V, ns)
    Y, moved, _ = reproduce_targets(_problem(tgt, F), V, keep, hold)
    assert len(self_intersecting_pairs(Y, F)) == 0 and np.array_equal(Y[ns:], V[ns:])
    assert (Y[dent, 2] > 0).all() and (Y[dent, 2] < 0.05 - 0.04).all()  # at least half way down
    far = np.linalg.norm(V[:ns, :2] - 0.5, axis=1) > 0.3
    assert np.array_equal(Y[:ns][far], tgt[:ns][far])


def test_reproduction_pushes_an_unconstrained_patch_out_of_the_way():
    """The sheet's target has a dent through a free patch below it: the dent goes all the way (bitwise on
    target) and the patch is pushed down under it, smoothly and by about the dent's depth, not held back."""
    V, F, ns = _sheet_over_patch()
    keep = np.zeros(len(V), dtype=bool)
    keep[:ns] = True
    tgt, _ = _dent(V, ns)
    Y, moved, pushed = reproduce_targets(_problem(tgt, F), V, keep, np.zeros(len(V), bool))
    assert len(self_intersecting_pairs(Y, F)) == 0 and np.array_equal(Y[:ns], tgt[:ns])
    assert pushed.any() and not pushed[:ns].any() and moved[pushed].all()
    assert (Y[ns:, 2] <= 0.0).all() and Y[ns:, 2].min() > -0.03 - 0.1  # down, about as deep as the dent
    assert np.abs(Y[ns:, :2] - V[ns:, :2]).max() < 0.02  # pushed along the separating axis (z)
