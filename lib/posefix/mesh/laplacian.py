"""Differential operators on a triangle mesh: gradient, mass, cotangent Laplacian, the umbrella (graph) Laplacian."""

import numpy as np
import scipy.sparse as sp

from posefix.mesh.geometry import face_cross


def gradient_operator(V, F):
    """Per-face gradient of piecewise-linear vertex functions.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
        Faces must have non-zero area.

    Returns
    -------
    (3 m, n) scipy.sparse.csr_matrix
        Row ``3 f + c`` gives component ``c`` (x, y, z) of the gradient on face ``f``; the gradient
        of the hat function of corner ``i`` is ``n x e_i / (2 A)`` with ``e_i`` the opposite edge.
    """
    m = len(F)
    cross = face_cross(V, F)
    dbl_area = np.linalg.norm(cross, axis=1)
    normal = cross / dbl_area[:, None]
    rows, cols, vals = [], [], []
    for i in range(3):
        opposite = V[F[:, (i + 2) % 3]] - V[F[:, (i + 1) % 3]]
        grad = np.cross(normal, opposite) / dbl_area[:, None]
        rows.append(3 * np.arange(m)[:, None] + np.arange(3)[None, :])
        cols.append(np.repeat(F[:, i:i + 1], 3, axis=1))
        vals.append(grad)
    rows, cols, vals = (np.concatenate(a).ravel() for a in (rows, cols, vals))
    return sp.csr_matrix((vals, (rows, cols)), shape=(3 * m, len(V)))


def face_mass(V, F):
    """Diagonal (3 m, 3 m) matrix of face areas, each repeated for the three gradient components."""
    area = 0.5 * np.linalg.norm(face_cross(V, F), axis=1)
    return sp.diags(np.repeat(area, 3))


def cotangent_laplacian(V, F):
    """Positive semi-definite cotangent Laplacian ``L = G^T M G``, (n, n) sparse csc.

    ``x^T L x`` is the Dirichlet energy of the piecewise-linear function ``x``; rows sum to zero.
    """
    G = gradient_operator(V, F)
    return (G.T @ face_mass(V, F) @ G).tocsc()


def uniform_laplacian(A):
    """Umbrella operator ``L s_i = mean of the neighbours' s - s_i``, (n, n) sparse csr.

    Parameters
    ----------
    A : (n, n) sparse bool
        Vertex adjacency (:func:`posefix.mesh.topology.vertex_adjacency`); isolated vertices get a
        zero row.
    """
    degree = np.asarray(A.sum(axis=1)).ravel()
    inv = np.where(degree > 0, 1.0 / np.maximum(degree, 1), 0.0)
    return (sp.diags(inv) @ A.astype(np.float64) - sp.diags((degree > 0).astype(np.float64))).tocsr()
