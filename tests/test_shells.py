"""Discrete-shell energy and Gauss–Newton (issue 6): angles, Jacobian, zero energy, a bent strip."""

import numpy as np
import pytest

from conftest import icosphere
from posefix.shells import (SolverSettings, deform_towards, dihedral_angles, gauss_newton, handle_vertices,
                            mesh_hinges, shell_energy, wrap_angle)


def _hinge(beta):
    """Two unit right triangles on the edge (0,0,0)-(1,0,0): faces (0, 1, 2) and (1, 0, 3), the
    second rotated about the edge by ``beta`` from flat (beta > 0: folding towards -z)."""
    V = np.array([[0.0, 0, 0], [1.0, 0, 0], [0.5, 1.0, 0], [0.5, -np.cos(beta), -np.sin(beta)]])
    return V, np.array([[0, 1, 2], [1, 0, 3]])


def test_wrap_angle_range_is_half_open():
    a = wrap_angle([np.pi, -np.pi, 3 * np.pi, 0.1 - 2 * np.pi, 2 * np.pi - 1e-12])
    assert np.allclose(a, [np.pi, np.pi, np.pi, 0.1, -1e-12])
    assert np.all((a > -np.pi) & (a <= np.pi))


def test_hinges_pair_the_two_faces_of_every_interior_edge():
    V, F = _hinge(0.3)
    H = mesh_hinges(F)
    assert H.hinges.tolist() == [[0, 1, 2, 3]] and H.hinge_faces.tolist() == [[0, 1]] and len(H.edges) == 5
    V, F = icosphere(1)
    H = mesh_hinges(F)
    assert len(H.hinges) == len(H.edges) == 3 * len(F) // 2  # closed: every edge is a hinge


@pytest.mark.parametrize("beta", [0.0, 1e-9, 0.4, -0.4, 1.5, np.pi - 1e-6, -(np.pi - 1e-6)])
def test_dihedral_angle_of_a_hand_built_hinge(beta):
    # face (0,1,2) has normal +z; rotating the second face down (beta > 0) makes the pair convex
    # seen along the normals: theta = +beta, including near-flat and near-folded (|theta| -> pi)
    V, F = _hinge(beta)
    theta = dihedral_angles(V, mesh_hinges(F).hinges)[0]
    assert theta == pytest.approx(beta, abs=1e-12)


def test_folded_hinge_wraps_around_pi():
    # just past the fold the angle jumps from +pi to -pi, the wrapped difference does not
    H = mesh_hinges(_hinge(0.0)[1]).hinges
    a = dihedral_angles(_hinge(np.pi - 1e-3)[0], H)[0]
    b = dihedral_angles(_hinge(np.pi + 1e-3)[0], H)[0]
    assert a == pytest.approx(np.pi - 1e-3) and b == pytest.approx(-np.pi + 1e-3)
    assert wrap_angle(b - a) == pytest.approx(2e-3)
    # the residual of a pose folded past pi towards a target just before it is small
    V0, F = _hinge(0.0)
    E = shell_energy(V0, F, _hinge(np.pi - 1e-3)[0], alpha=1.0, k_bend=1.0)
    r = E.residuals(_hinge(np.pi + 1e-3)[0])
    assert abs(r[-1]) < 1e-2 * E.w_bend[0]


def test_convex_closed_surface_has_positive_dihedral_angles():
    V, F = icosphere(1)  # outward-facing normals
    assert np.all(dihedral_angles(V, mesh_hinges(F).hinges) > 0)


def _random_mesh(seed):
    V, F = icosphere(1)
    rng = np.random.default_rng(seed)
    return V + 0.05 * rng.normal(size=V.shape), F, V + 0.2 * rng.normal(size=V.shape)


@pytest.mark.parametrize("seed", [0, 1])
def test_jacobian_equals_finite_differences(seed):
    V_ref, F, V_pose = _random_mesh(seed)
    E = shell_energy(V_ref, F, V_pose, alpha=0.5, k_stretch=1.0, k_bend=0.1)
    X = V_ref + 0.5 * (V_pose - V_ref)
    J = E.jacobian(X).toarray()
    h = 1e-6
    fd = np.empty_like(J)
    for col in range(J.shape[1]):
        Xp, Xm = X.copy(), X.copy()
        Xp.reshape(-1)[col] += h
        Xm.reshape(-1)[col] -= h
        fd[:, col] = wrap_angle(E.residuals(Xp) - E.residuals(Xm)) / (2 * h)  # wrap: no 2 pi jumps
    assert np.abs(J - fd).max() <= 1e-6 * np.abs(fd).max()


def test_zero_energy_and_no_iteration_when_the_example_is_the_reference():
    V, F = icosphere(2)
    h = handle_vertices(V)
    for alpha in (0.5, 1.0):
        E = shell_energy(V, F, V, alpha)
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


def test_handles_are_far_apart_and_deterministic():
    V, F = _strip()
    h = handle_vertices(V)
    assert len(set(h.tolist())) == 3 and h.tolist() == handle_vertices(V).tolist()
    assert np.linalg.norm(V[h[0]] - V[h[1]]) == pytest.approx(np.linalg.norm(V.max(0) - V.min(0)))
