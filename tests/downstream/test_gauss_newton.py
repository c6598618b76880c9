"""Gauss-Newton with step halving: exact solutions, convergence and the reasons a run stops."""

import numpy as np
import pytest

from conftest import icosphere
from posefix.downstream.check import deform_towards, handle_vertices
from posefix.downstream.gauss_newton import STOP_REASONS, SolverSettings, gauss_newton, unknowns
from posefix.mesh.shells import dihedral_angles, mesh_hinges, shell_energy


def test_zero_energy_and_no_iteration_when_the_example_is_the_reference():
    V, F = icosphere(2)
    h = handle_vertices(V)
    for alpha in (0.5, 1.0):
        E = shell_energy(V, F, V, alpha, k_bend=1e-2)
        assert E.energy(V) == 0.0
        res = gauss_newton(E, V, h, V[h], F)
        assert res.iterations == 0 and res.converged and res.errors.tolist() == [0.0]
        assert np.array_equal(res.V, V)


def _strip(n=12):
    """A flat strip of 2 n triangles along x (width 1, length n / 2), (n + 1) * 2 vertices."""
    x = np.arange(n + 1) / 2.0
    V = np.concatenate([np.c_[x, np.zeros_like(x), np.zeros_like(x)], np.c_[x, np.ones_like(x), np.zeros_like(x)]])
    a, b = np.arange(n), np.arange(n) + n + 1
    F = np.concatenate([np.c_[a, a + 1, b + 1], np.c_[a, b + 1, b]])
    return V, F


def _bend(V, angle, at):
    """Rotate the part x > at of the strip about the line x = at, y arbitrary (the y axis)."""
    W = V.copy()
    right = V[:, 0] > at
    c, s = np.cos(angle), np.sin(angle)
    dx, z = V[right, 0] - at, V[right, 2]
    W[right, 0], W[right, 2] = at + c * dx - s * z, s * dx + c * z
    return W


@pytest.mark.parametrize("angle", [0.5, 1.2, 2.0, -2.0])
def test_gauss_newton_bends_a_strip_to_the_exact_target(angle):
    # from the flat strip with three corners pinned at the bent ones (beyond about 2.2 rad Gauss-
    # Newton finds another minimum: a fold that large is not a small-step problem)
    V, F = _strip()
    target = _bend(V, angle, at=3.0)
    res = deform_towards(V, F, target, alpha=1.0, k_bend=1e-2)
    assert res.converged and res.reason == "converged", res.reason
    assert res.errors[-1] <= SolverSettings().energy_tol
    assert np.abs(res.V - target).max() < 1e-7
    # the strip's fold line is one hinge row bent by the angle, everything else flat
    theta = dihedral_angles(res.V, mesh_hinges(F).hinges)
    assert np.isclose(np.abs(theta).max(), abs(angle)) and np.sum(np.abs(theta) > 1e-6) == 1


def test_half_way_example_converges_with_a_full_step():
    V, F = _strip()
    res = deform_towards(V, F, _bend(V, 1.0, at=3.0), alpha=0.5, k_bend=1e-2)
    assert res.converged and res.steps[-1] == 1.0 and res.gradient_reduction >= 1e4
    # in between: the targets ask for half the fold, the pinned corners (linear blend, a shorter
    # chord) pull towards less
    theta = dihedral_angles(res.V, mesh_hinges(F).hinges)
    assert 0.1 < np.abs(theta).max() < 1.0


def test_a_run_stopped_by_max_iters_is_not_converged():
    V, F = _strip()
    settings = SolverSettings(max_iters=1)
    res = deform_towards(V, F, _bend(V, 2.5, at=3.0), alpha=1.0, k_bend=1e-2, settings=settings)
    assert not res.converged and res.reason == "max_iters" and res.iterations == 1


def test_stop_reasons_are_the_codes_of_the_artifact():
    assert STOP_REASONS[0] == "converged" and len(set(STOP_REASONS)) == len(STOP_REASONS)


def test_unknowns_are_the_free_coordinates_vertex_by_vertex():
    V, F = icosphere(2)
    h = handle_vertices(V)
    cols = unknowns(shell_energy(V, F, V, 1.0, k_bend=1e-2).jacobian(V), h)
    free = np.setdiff1d(np.arange(len(V)), h)
    assert np.array_equal(np.sort(cols), np.sort((3 * free[:, None] + np.arange(3)).reshape(-1)))
    assert np.array_equal(cols.reshape(-1, 3), 3 * (cols[::3] // 3)[:, None] + np.arange(3))
