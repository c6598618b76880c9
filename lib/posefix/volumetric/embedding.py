"""Points in a tet mesh: barycentric coordinates in the tet that contains them (or the nearest).

S4's point handles (markers) are such fixed combinations of tet vertices; the smooth surface transfer
(:mod:`posefix.volumetric.transfer`) falls back to them where no boundary face is near.
"""

import numpy as np
from scipy.spatial import cKDTree

from posefix.volumetric.operators import edge_matrices


def barycentric_embedding(X, T, P, candidates=16):
    """For every point the tet that contains it best and its barycentric coordinates there.

    The tet is the one, among the ``candidates`` nearest by centroid, whose smallest barycentric coordinate is
    largest: inside it (all >= 0) when some candidate contains the point, else the least-outside one
    (coordinates extrapolate linearly).

    Parameters
    ----------
    X : (n, 3) float
        Tet-mesh vertices; ``T`` (t, 4) int its tets.
    P : (k, 3) float
        Points to embed.

    Returns
    -------
    tets : (k,) int64
    weights : (k, 4) float
        Barycentric coordinates (sum 1): ``P = sum_c weights[:, c] X[T[tets, c]]``.
    """
    inv = np.linalg.inv(edge_matrices(X, T))
    _, near = cKDTree(X[T].mean(axis=1)).query(P, k=min(candidates, len(T)))
    near = near.reshape(len(P), -1)
    local = np.einsum("kcij,kcj->kci", inv[near], P[:, None, :] - X[T[near, 0]])  # coordinates 1-3
    weights = np.concatenate([1.0 - local.sum(axis=2, keepdims=True), local], axis=2)
    best = np.argmax(weights.min(axis=2), axis=1)
    rows = np.arange(len(P))
    return near[rows, best].astype(np.int64), weights[rows, best]


def embedded_points(Y, T, tets, weights):
    """Positions (k, 3) of embedded points for tet-mesh vertices ``Y`` (n, 3)."""
    return np.einsum("kc,kci->ki", weights, Y[T[tets]])
