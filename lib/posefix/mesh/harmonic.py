"""Harmonic extension of vertex values over a mesh graph (uniform Laplacian, Dirichlet data)."""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from posefix.mesh.sparse import factorized
from posefix.mesh.tolerances import ROUNDOFF


def harmonic_extension(A, values, known):
    """Extend values given on ``known`` vertices to the others by solving ``L u = 0`` there.

    ``L = D - A`` is the uniform (graph) Laplacian, so every unknown vertex ends at the mean of
    its neighbours: the smoothest blend of the known values.

    Parameters
    ----------
    A : (n, n) sparse bool
        Vertex adjacency (:func:`posefix.mesh.topology.vertex_adjacency`).
    values : (n, k) float
        Values; only the rows of ``known`` are read.
    known : (n,) bool
        Dirichlet vertices.

    Returns
    -------
    (n, k) float
        ``values`` on ``known``; the harmonic extension on unknown vertices connected to a known
        one; 0 on unknown components without any known vertex (no data to extend).
    """
    A = sp.csr_matrix(A, dtype=np.float64)
    out = np.zeros_like(values, dtype=np.float64)
    out[known] = values[known]
    unknown = np.flatnonzero(~known)
    if len(unknown) == 0:
        return out
    A_uu = A[unknown][:, unknown]
    count, label = connected_components(A_uu, directed=False)
    anchored = np.zeros(count, dtype=bool)
    anchored[np.unique(label[np.asarray(A[unknown][:, known].sum(axis=1)).ravel() > 0])] = True
    solve = unknown[anchored[label]]
    if len(solve) == 0:
        return out
    degree = np.asarray(A[solve].sum(axis=1)).ravel()
    L_ss = (sp.diags(degree) - A[solve][:, solve]).tocsc()
    out[solve] = factorized(L_ss, "MMD_AT_PLUS_A", symmetric=True).solve(A[solve][:, known] @ out[known])
    return out


def biharmonic_extension(A, values, known, unknown):
    """Extend values on ``known`` vertices over ``unknown`` ones by minimizing ``|L u|^2``, u = 0 elsewhere.

    The smooth (C1-like) counterpart of :func:`harmonic_extension` for point-like data: a single
    known vertex becomes a smooth bump, not a cone, and the bump fades out to zero at the border
    of ``unknown``.

    Parameters
    ----------
    A : (n, n) sparse bool
        Vertex adjacency.
    values : (n, k) float
        Values; only the rows of ``known`` are read.
    known, unknown : (n,) bool
        Dirichlet vertices and the vertices to solve for (disjoint); all others are 0.

    Returns
    -------
    (n, k) float
    """
    A = sp.csr_matrix(A, dtype=np.float64)
    out = np.zeros_like(values, dtype=np.float64)
    out[known] = values[known]
    solve = np.flatnonzero(unknown & ~known)
    if len(solve) == 0:
        return out
    L = (sp.diags(np.asarray(A.sum(axis=1)).ravel()) - A).tocsc()
    Q = (L.T @ L).tocsr()
    Q_ss = Q[solve][:, solve] + sp.identity(len(solve)) * ROUNDOFF  # regular where a part touches no zero vertex
    out[solve] = factorized(Q_ss.tocsc(), "MMD_AT_PLUS_A", symmetric=True).solve(
        -(Q[solve][:, np.flatnonzero(known)] @ out[known]))
    return out
