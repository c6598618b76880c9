"""Discrete-shell energy (issue 6): hinges, dihedral angles and their wrapping, the analytic Jacobian."""

import numpy as np
import pytest

from conftest import icosphere
from posefix.mesh.shells import dihedral_angles, mesh_hinges, shell_energy, wrap_angle


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
