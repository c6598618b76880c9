"""Differential operators: gradient of linear functions, L = G^T M G against the cotangent formula."""

import numpy as np

from conftest import icosphere
from posefix.mesh.geometry import face_areas
from posefix.mesh.laplacian import cotangent_laplacian, face_mass, gradient_operator


def test_gradient_of_a_linear_function_is_exact():
    V, F = icosphere(2)
    a = np.array([0.3, -1.2, 2.0])
    g = (gradient_operator(V, F) @ (V @ a)).reshape(-1, 3)
    normals = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    tangential = a - (normals @ a)[:, None] * normals
    assert np.allclose(g, tangential, atol=1e-12)


def test_one_triangle_laplacian_is_the_cotangent_formula():
    V = np.array([[0.0, 0, 0], [2.0, 0, 0], [0.5, 1.5, 0]])
    F = np.array([[0, 1, 2]])
    L = cotangent_laplacian(V, F).toarray()
    expected = np.zeros((3, 3))
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        u, v = V[j] - V[i], V[k] - V[i]
        cot = u @ v / np.linalg.norm(np.cross(u, v))  # cotangent of the angle at i, opposite edge jk
        expected[j, k] = expected[k, j] = -0.5 * cot
    expected -= np.diag(expected.sum(1))
    assert np.allclose(L, expected, atol=1e-14)


def test_laplacian_identities_on_a_sphere():
    V, F = icosphere(3)
    G, M = gradient_operator(V, F), face_mass(V, F)
    L = cotangent_laplacian(V, F)
    assert np.allclose((L - G.T @ M @ G).toarray(), 0.0, atol=1e-12)
    assert np.allclose(L @ np.ones(len(V)), 0.0, atol=1e-12)
    assert np.allclose((L - L.T).toarray(), 0.0, atol=1e-14)
    # Dirichlet energy of a linear function = |tangential gradient|^2 integrated
    x = V[:, 0]
    assert np.isclose(x @ (L @ x), np.sum(face_areas(V, F) * np.sum((G @ x).reshape(-1, 3) ** 2, 1)))


def test_uniform_laplacian_of_one_triangle_and_an_isolated_vertex():
    from posefix.mesh.laplacian import uniform_laplacian
    from posefix.mesh.topology import vertex_adjacency
    L = uniform_laplacian(vertex_adjacency(np.array([[0, 1, 2]]), 4)).toarray()
    assert np.allclose(L[:3, :3], [[-1, 0.5, 0.5], [0.5, -1, 0.5], [0.5, 0.5, -1]]) and not L[3].any()
