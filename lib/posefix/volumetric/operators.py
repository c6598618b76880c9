"""Tetrahedral differential operators (S4 §2.2, Eq. 2.2-2.5): per-tet gradients, volumes, the Laplacian.

Tets ``T`` (t, 4) int are positively oriented: ``det(x1 - x0, x2 - x0, x3 - x0) > 0``.
"""

import numpy as np
import scipy.sparse as sp


def edge_matrices(X, T):
    """Columns ``x_i - x_0`` (i = 1, 2, 3) of every tet, (t, 3, 3) float."""
    return np.stack([X[T[:, i]] - X[T[:, 0]] for i in (1, 2, 3)], axis=2)


def tet_volumes(X, T):
    """Signed volumes ``det(E) / 6`` of the tets, (t,) float (positive for positively oriented tets)."""
    return np.linalg.det(edge_matrices(X, T)) / 6.0


def tet_gradient_operator(X, T):
    """Per-tet gradients of piecewise-linear vertex functions (S4's ``G_j``, Eq. 2.3), (3 t, n) sparse csr.

    Row ``3 j + c`` gives component ``c`` of the gradient on tet ``j``: for corners 1-3 the rows of
    ``E_j^-1`` (``E_j`` the edge matrix of :func:`edge_matrices`), for corner 0 minus their sum.

    Parameters
    ----------
    X : (n, 3) float
    T : (t, 4) int
        Non-degenerate tets.

    Examples
    --------
    >>> G = tet_gradient_operator(X, T)          # doctest: +SKIP
    >>> (G @ X).reshape(-1, 3, 3)                # identity per tet: the gradient of the coordinates  # doctest: +SKIP
    """
    inv = np.linalg.inv(edge_matrices(X, T))  # row k of E^-1: gradient of the hat function of corner k + 1
    grads = np.concatenate([-inv.sum(axis=1, keepdims=True), inv], axis=1)  # (t, 4 corners, 3)
    t = len(T)
    rows = np.broadcast_to(3 * np.arange(t)[:, None, None] + np.arange(3)[None, None, :], (t, 4, 3))
    cols = np.broadcast_to(T[:, :, None], (t, 4, 3))
    return sp.csr_matrix((grads.ravel(), (rows.ravel(), cols.ravel())), shape=(3 * t, len(X)))


def tet_mass(X, T, weights=None):
    """S4's ``D``: tet volumes, each repeated for the three gradient components, (3 t, 3 t) sparse diagonal.

    ``weights`` (t,) scale them: a tet's stiffness (S4 §2.3.2 scales ``G_j`` and ``g_j``, the same as
    scaling ``D`` by the square).
    """
    vol = np.abs(tet_volumes(X, T)) * (1.0 if weights is None else weights)
    return sp.diags(np.repeat(vol, 3))


def tet_laplacian(X, T, weights=None):
    """The tetrahedral Laplacian ``L = G^T D G`` (S4 Eq. 2.4), (n, n) sparse csc, positive semi-definite.

    ``x^T L x`` is the Dirichlet energy of the piecewise-linear function ``x``; rows sum to zero. On a
    single tet ``L_ab = -l_cd cot(theta_cd) / 6`` with ``cd`` the edge opposite ``ab`` and ``theta_cd``
    the dihedral angle at it.
    """
    G = tet_gradient_operator(X, T)
    return (G.T @ tet_mass(X, T, weights) @ G).tocsc()


def tet_adjacency(T):
    """Tets sharing a face, (t, t) sparse bool (symmetric)."""
    faces = np.sort(np.concatenate([T[:, [1, 2, 3]], T[:, [0, 2, 3]], T[:, [0, 1, 3]], T[:, [0, 1, 2]]]), axis=1)
    owner = np.tile(np.arange(len(T)), 4)
    order = np.lexsort(faces.T[::-1])
    faces, owner = faces[order], owner[order]
    shared = np.flatnonzero((faces[1:] == faces[:-1]).all(axis=1))
    a, b = owner[shared], owner[shared + 1]
    A = sp.coo_matrix((np.ones(len(a), dtype=bool), (a, b)), shape=(len(T), len(T)))
    return (A + A.T).tocsr()


def differential_coordinates(G, D, gradients):
    """``delta = G^T D g`` (S4 Eq. 2.5) for per-tet coordinate gradients ``g`` (t, 3, 3), (n, 3) float.

    ``gradients[j]`` is the 3x3 gradient of the three coordinate functions on tet ``j`` (column ``c``: the
    gradient of coordinate ``c``): the identity at rest, ``R_j^T`` for a tet turned by ``R_j``.
    """
    return G.T @ (D @ gradients.reshape(-1, 3))
