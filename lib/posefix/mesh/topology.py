"""Mesh connectivity: vertex and face adjacency, edges, k-ring growth, connected components."""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components


def vertex_adjacency(F, n):
    """Vertex-vertex adjacency of a triangle mesh.

    Parameters
    ----------
    F : (m, 3) int
    n : int
        Number of vertices.

    Returns
    -------
    (n, n) scipy.sparse.csr_matrix of bool
        Symmetric, True where two vertices share an edge; the diagonal is False.
    """
    i = F[:, [0, 1, 2, 1, 2, 0]].ravel()
    j = F[:, [1, 2, 0, 0, 1, 2]].ravel()
    A = sp.coo_matrix((np.ones(len(i), dtype=bool), (i, j)), shape=(n, n)).tocsr()
    A.setdiag(False)
    A.eliminate_zeros()
    return A


def grow_rings(mask, adjacency, rings):
    """Add ``rings`` rings of neighbours to a vertex selection.

    Parameters
    ----------
    mask : (n,) bool
        Selected vertices.
    adjacency : (n, n) sparse bool
        From :func:`vertex_adjacency`.
    rings : int
        Number of rings to add (0 returns a copy).

    Returns
    -------
    (n,) bool
    """
    grown = np.asarray(mask, dtype=bool).copy()
    for _ in range(rings):
        grown |= adjacency @ grown
    return grown


def half_edges(F):
    """The three edges of every face as sorted vertex pairs, (3 m, 2) int; rows 3f..3f+2 are face f's."""
    return np.sort(F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)


def edges(F):
    """Unique undirected edges, (e, 2) int64 with ``e[:, 0] < e[:, 1]``, sorted."""
    return np.unique(half_edges(F), axis=0)


def face_adjacency(F):
    """Pairs of faces that share an edge.

    Returns
    -------
    (k, 2) int64
        Unique face index pairs ``(f, g)`` with ``f < g``. The faces around a non-manifold edge
        (three or more) are chained in index order, which keeps them connected.
    """
    E = half_edges(F)
    face = np.repeat(np.arange(len(F)), 3)
    order = np.lexsort((face, E[:, 1], E[:, 0]))
    E, face = E[order], face[order]
    same = np.all(E[1:] == E[:-1], axis=1)
    P = np.stack([face[:-1][same], face[1:][same]], axis=1)
    P = np.sort(P, axis=1)
    return np.unique(P[P[:, 0] != P[:, 1]], axis=0).astype(np.int64)


def vertex_components(F, n):
    """Connected components of the vertex graph.

    Returns
    -------
    labels : (n,) int
        Component id per vertex; isolated vertices get a component of their own.
    count : int
    """
    count, labels = connected_components(vertex_adjacency(F, n), directed=False)
    return labels, count


def selection_components(selected, A, links=None):
    """Connected components of a vertex selection, through mesh edges and extra vertex links.

    Parameters
    ----------
    selected : (n,) bool
    A : (n, n) sparse bool
        Vertex adjacency (:func:`vertex_adjacency`).
    links : (k, 2) int, optional
        Extra vertex pairs that count as connected (e.g. one vertex of each of two intersecting
        faces); pairs with a vertex outside the selection are ignored.

    Returns
    -------
    list of (c_i,) int64
        Vertex indices of each component, the components ordered by their smallest vertex.
    """
    idx = np.flatnonzero(selected)
    if len(idx) == 0:
        return []
    graph = A[idx][:, idx].tocoo()
    if links is not None and len(links):
        pos = np.full(len(selected), -1)
        pos[idx] = np.arange(len(idx))
        a, b = pos[links[:, 0]], pos[links[:, 1]]
        ok = (a >= 0) & (b >= 0)
        graph = sp.coo_matrix((np.ones(graph.nnz + ok.sum()), (np.concatenate([graph.row, a[ok]]),
                                                                 np.concatenate([graph.col, b[ok]]))),
                              shape=graph.shape)
    count, labels = connected_components(graph, directed=False)
    return [idx[labels == c] for c in range(count)]
