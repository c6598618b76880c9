"""Tetrahedral operators: gradients of linear functions, volumes, the Laplacian's closed form on one tet."""

import numpy as np
import pytest

from posefix.volumetric.operators import (differential_coordinates, tet_gradient_operator, tet_laplacian, tet_mass,
                                          tet_volumes)
from posefix.volumetric.shapes import tet_cylinder, tet_grid

ONE_TET = np.array([[0.0, 0, 0], [1.3, 0.1, 0], [0.2, 0.9, 0.1], [0.3, 0.2, 1.1]]), np.array([[0, 1, 2, 3]])


def dihedral_cotangent(X, a, b, c, d):
    """cot of the dihedral angle at edge (c, d) between the faces (c, d, a) and (c, d, b)."""
    e = X[d] - X[c]
    u, w = X[a] - X[c], X[b] - X[c]
    u, w = u - e * (u @ e) / (e @ e), w - e * (w @ e) / (e @ e)  # perpendicular to the edge
    cos = u @ w / np.linalg.norm(u) / np.linalg.norm(w)
    return cos / np.sqrt(1.0 - cos ** 2)


def test_the_laplacian_of_one_tet_is_the_cotangent_formula():
    X, T = ONE_TET
    L = tet_laplacian(X, T).toarray()
    for a in range(4):
        for b in range(a + 1, 4):
            c, d = sorted(set(range(4)) - {a, b})
            expected = -np.linalg.norm(X[d] - X[c]) * dihedral_cotangent(X, a, b, c, d) / 6.0
            assert L[a, b] == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("mesh", [tet_grid((4, 2, 3), (2.0, 1.0, 1.5)), tet_cylinder(0.5, 3.0, 6, 2)])
def test_the_laplacian_is_symmetric_semidefinite_with_the_constants_in_its_kernel(mesh):
    X, T = mesh
    L = tet_laplacian(X, T)
    assert abs(L - L.T).max() <= 1e-13 and np.abs(L @ np.ones(len(X))).max() <= 1e-12
    eigenvalues = np.linalg.eigvalsh(L.toarray())
    assert eigenvalues[0] >= -1e-12 and eigenvalues[1] > 1e-6  # one connected mesh: a single zero


def test_gradients_of_linear_functions_are_exact_and_the_rest_is_its_own_solution():
    X, T = tet_cylinder(0.5, 2.0, 4, 2)
    assert np.all(tet_volumes(X, T) > 0)
    G, D = tet_gradient_operator(X, T), tet_mass(X, T)
    A = np.array([[1.0, 2, 0], [0, 1, -1], [3, 0, 2]])
    assert np.abs((G @ (X @ A.T)).reshape(-1, 3, 3) - A.T).max() <= 1e-12  # columns: gradients of x_c
    delta = differential_coordinates(G, D, np.broadcast_to(np.eye(3), (len(T), 3, 3)))
    assert np.abs(delta - tet_laplacian(X, T) @ X).max() <= 1e-12


def test_the_grid_fills_its_box_with_positive_tets():
    X, T = tet_grid((3, 4, 5), (3.0, 2.0, 1.0))
    volumes = tet_volumes(X, T)
    assert len(T) == 6 * 60 and np.all(volumes > 0) and volumes.sum() == pytest.approx(6.0, rel=1e-12)


def test_embedded_points_follow_an_affine_map_exactly_inside_and_outside():
    from posefix.volumetric.embedding import barycentric_embedding, embedded_points
    X, T = tet_grid((4, 2, 2), (4.0, 1.0, 1.0))
    rng = np.random.default_rng(2)
    P = np.column_stack([rng.uniform(-0.2, 4.2, 300), rng.uniform(-0.1, 1.1, 300), rng.uniform(0, 1, 300)])
    tets, weights = barycentric_embedding(X, T, P)
    assert np.allclose(weights.sum(axis=1), 1.0) and np.abs(embedded_points(X, T, tets, weights) - P).max() < 1e-12
    inside = (P[:, 0] > 0) & (P[:, 0] < 4) & (P[:, 1] > 0) & (P[:, 1] < 1)
    assert np.all(weights[inside].min(axis=1) >= -1e-12)  # the containing tet
    A = np.array([[1.0, 0.3, 0], [0, 2, 0], [0.1, 0, 1]])
    assert np.abs(embedded_points(X @ A.T, T, tets, weights) - P @ A.T).max() < 1e-12
