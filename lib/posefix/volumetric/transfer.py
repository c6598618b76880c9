"""S4's high-resolution transfer (§2.4, Eq. 2.9-2.12): a smooth sparse map from tet-mesh vertices to a fine mesh.

Every fine vertex ``v`` is a blend of its barycentric coordinates with respect to every tet that has a
boundary face whose centre lies within ``radius`` of it, weighted by Wendland's function of that distance:
``B[v] = sum_j phi(d_j) c_j(v) / sum_j phi(d_j)``. Each ``c_j`` reproduces affine maps, so ``B`` does too
(rows sum to 1, the rest pose comes back exactly), and the weights vanish smoothly at ``radius``, so the
map is continuous where the piecewise-linear embedding of the nearest tet is not. Vertices with no
boundary face within ``radius`` take that embedding.
"""

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from posefix.volumetric.embedding import barycentric_embedding
from posefix.volumetric.operators import edge_matrices


def wendland(d, radius):
    """Wendland's C2 function ``(1 - d/r)^4 (4 d/r + 1)`` for ``d < r``, else 0 (S4 Eq. 2.10)."""
    u = np.clip(np.asarray(d) / radius, 0.0, 1.0)
    return (1.0 - u) ** 4 * (4.0 * u + 1.0)


def boundary_faces(T):
    """Faces of the tets that no other tet shares: (b, 3) vertex ids and the tet of each, (b,) int64."""
    faces = np.concatenate([T[:, [1, 2, 3]], T[:, [0, 2, 3]], T[:, [0, 1, 3]], T[:, [0, 1, 2]]])
    owner = np.tile(np.arange(len(T)), 4)
    _, inverse, counts = np.unique(np.sort(faces, axis=1), axis=0, return_inverse=True, return_counts=True)
    single = counts[inverse.ravel()] == 1
    return faces[single], owner[single]


def transfer_matrix(X, T, V, radius):
    """The sparse map ``B`` (n, k) with ``V = B X`` at rest and ``V' = B X'`` for deformed tet vertices ``X'``.

    Parameters
    ----------
    X : (k, 3) float
        Tet-mesh vertices at rest; ``T`` (t, 4) int its tets.
    V : (n, 3) float
        Fine-mesh vertices at rest.
    radius : float
        Support of the weights (model units; S4: 5 % of the bbox diagonal).

    Returns
    -------
    scipy.sparse.csr_matrix
    """
    faces, owner = boundary_faces(T)
    centres = X[faces].mean(axis=1)
    near = cKDTree(centres).query_ball_point(V, radius, return_sorted=False)
    counts = np.fromiter(map(len, near), dtype=np.int64, count=len(V))
    pairs = np.concatenate([np.asarray(n, dtype=np.int64) for n in near]) if counts.any() else np.zeros(0, np.int64)
    rows = np.repeat(np.arange(len(V)), counts)  # (vertex, boundary face) pairs, grouped by vertex
    weight = wendland(np.linalg.norm(V[rows] - centres[pairs], axis=1), radius)
    total = np.bincount(rows, weights=weight, minlength=len(V))
    values = _blended_coordinates(X, T, V, rows, owner[pairs], weight / np.where(total > 0, total, 1.0)[rows])
    # W (n, 4t): column 4 j + c holds the weighted coordinate of corner c of tet j (repeats summed by the
    # product); S (4t, k) sends it to that corner's vertex. B = W S is a sparse product, no sort of the
    # (vertex, corner) entries.
    indptr = np.concatenate([[0], np.cumsum(4 * counts)])
    W = sp.csr_matrix((values.ravel(), (4 * owner[pairs][:, None] + np.arange(4)).ravel(), indptr),
                      shape=(len(V), 4 * len(T)))
    S = sp.csr_matrix((np.ones(T.size), T.ravel(), np.arange(T.size + 1)), shape=(T.size, len(X)))
    B = W @ S
    lonely = np.flatnonzero(total == 0)
    if len(lonely):
        tet, bary = barycentric_embedding(X, T, V[lonely])
        B = B + sp.csr_matrix((bary.ravel(), (np.repeat(lonely, 4), T[tet].ravel())), shape=B.shape)
    B = B.tocsr()
    B.sort_indices()
    return B


def _blended_coordinates(X, T, V, rows, tets, weight, chunk=1 << 20):
    """``weight[:, None] *`` the barycentric coordinates of ``V[rows]`` in ``T[tets]``, (p, 4), in chunks."""
    inverse = np.linalg.inv(edge_matrices(X, T))
    out = np.empty((len(rows), 4))
    for s in range(0, len(rows), chunk):
        r, t = rows[s:s + chunk], tets[s:s + chunk]
        local = np.einsum("kij,kj->ki", inverse[t], V[r] - X[T[t, 0]])
        out[s:s + chunk, 0] = 1.0 - local.sum(axis=1)
        out[s:s + chunk, 1:] = local
        out[s:s + chunk] *= weight[s:s + chunk, None]
    return out
