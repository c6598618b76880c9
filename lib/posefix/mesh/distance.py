"""Distance from points to a triangle mesh, exact (closest face among those that can be closest)."""

import itertools

import numpy as np
from scipy.spatial import cKDTree

from posefix.mesh.geometry import point_triangle_distance

_POINTS_PER_CHUNK = 2048


def surface_distance_below(V, F, P, limit):
    """Distance from points to a triangle mesh, exact where it is below a per-point limit.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    P : (k, 3) float
    limit : (k,) float
        Non-negative bounds.

    Returns
    -------
    (k,) float
        ``min(limit[i], distance from P[i] to the closest face)``, exact up to rounding.

    Notes
    -----
    A face within ``rho`` of a point has its centroid within ``rho + r_f`` (``r_f``: largest
    centroid-corner distance of the face). The faces are grouped by ``r_f`` in powers of two, one
    k-d tree of centroids per group, so each point measures only the faces whose centroid is within
    ``rho`` plus at most twice their own ``r_f``, with ``rho`` the limit or the nearest vertex
    distance, whichever is smaller: the cost follows the local edge length, not the longest edge.
    """
    out = np.array(limit, dtype=np.float64)
    if len(P) == 0 or len(F) == 0:
        return out
    out = np.minimum(out, cKDTree(V).query(P)[0])  # the nearest vertex bounds the search
    centroid = V[F].mean(axis=1)
    spread = np.linalg.norm(V[F] - centroid[:, None], axis=2).max(axis=1)
    group = np.frexp(np.maximum(spread, np.finfo(float).tiny))[1]
    for g in np.unique(group):
        faces = np.flatnonzero(group == g)
        tree = cKDTree(centroid[faces])
        for s in range(0, len(P), _POINTS_PER_CHUNK):
            idx = np.arange(s, min(s + _POINTS_PER_CHUNK, len(P)))
            point, face = _pairs_within(tree, P[idx], out[idx] + spread[faces].max())
            face = faces[face]
            d = point_triangle_distance(P[idx][point], V[F[face, 0]], V[F[face, 1]], V[F[face, 2]])
            np.minimum.at(out, idx[point], d)
    return out


def _pairs_within(tree, P, radius):
    """(point, item) index pairs of the items of ``tree`` within ``radius`` (k,) of each point."""
    lists = tree.query_ball_point(P, radius)
    count = np.fromiter(map(len, lists), dtype=np.int64, count=len(lists))
    item = np.fromiter(itertools.chain.from_iterable(lists), dtype=np.int64, count=int(count.sum()))
    return np.repeat(np.arange(len(P)), count), item
