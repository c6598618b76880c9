"""Near contacts: vertices that come close to a geodesically distant part of the surface.

A vertex ``v`` is *in contact* in a frame when some face lies within Euclidean distance
``distance`` of it there, while that face is *non-neighbouring*: its nearest vertex is at least
``radius`` away from ``v`` along the edges of the **reference** mesh (an upper bound of the
geodesic distance). Edge-path distance is used rather than a k-ring because edge lengths vary by
orders of magnitude on real meshes (1e-4 d to 0.056 d on the lion).
"""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from posefix.bvh import build_box_tree, cross_overlapping_pairs
from posefix.geometry import point_triangle_distance
from posefix.topology import edges

_DIJKSTRA_ROWS = 128


def close_vertex_face_pairs(V, F, distance):
    """Vertex-face pairs closer than ``distance``, the vertex not being a corner of the face.

    Returns
    -------
    (k, 2) int64
        Columns: vertex index, face index; sorted.
    """
    T = V[F]
    faces = build_box_tree(T.min(axis=1), T.max(axis=1))
    points = build_box_tree(V - distance, V + distance)
    P = cross_overlapping_pairs(points, faces)
    P = P[~np.any(F[P[:, 1]] == P[:, :1], axis=1)]
    d = point_triangle_distance(V[P[:, 0]], T[P[:, 1], 0], T[P[:, 1], 1], T[P[:, 1], 2])
    return P[d < distance]


def edge_graph(V, F):
    """Symmetric sparse (n, n) matrix of edge lengths of a mesh."""
    E = edges(F)
    w = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    G = sp.coo_matrix((w, (E[:, 0], E[:, 1])), shape=(len(V), len(V)))
    return (G + G.T).tocsr()


def non_neighbouring(pairs, F, graph, radius):
    """Mask of vertex-face pairs whose face is at least ``radius`` away along ``graph``.

    Parameters
    ----------
    pairs : (k, 2) int
        Vertex, face.
    F : (m, 3) int
    graph : (n, n) sparse
        Edge lengths of the reference (:func:`edge_graph`).
    radius : float

    Returns
    -------
    (k,) bool
    """
    keep = np.ones(len(pairs), dtype=bool)
    sources = np.unique(pairs[:, 0])
    for start in range(0, len(sources), _DIJKSTRA_ROWS):
        chunk = sources[start:start + _DIJKSTRA_ROWS]
        dist = dijkstra(graph, directed=False, indices=chunk, limit=radius)
        rows = np.searchsorted(chunk, pairs[:, 0])
        inside = (rows < len(chunk)) & (chunk[np.minimum(rows, len(chunk) - 1)] == pairs[:, 0])
        idx = np.flatnonzero(inside)
        near = dist[rows[idx][:, None], F[pairs[idx, 1]]].min(axis=1) < radius
        keep[idx[near]] = False
    return keep


def contact_vertices(frames, F, V_ref, distance, radius, log=None):
    """Per-frame near-contact vertices.

    Parameters
    ----------
    frames : (K, n, 3) float
    F : (m, 3) int
    V_ref : (n, 3) float
        Reference, for the geodesic neighbourhoods.
    distance, radius : float
        Contact distance and neighbourhood radius, in length units.

    Returns
    -------
    (K, n) bool
    """
    graph = edge_graph(V_ref, F)
    close = [close_vertex_face_pairs(V, F, distance) for V in frames]
    frame = np.repeat(np.arange(len(frames)), [len(p) for p in close])
    pairs = np.concatenate(close)
    keep = non_neighbouring(pairs, F, graph, radius)  # one geodesic search per vertex, all frames
    out = np.zeros(frames.shape[:2], dtype=bool)
    out[frame[keep], pairs[keep, 0]] = True
    if log is not None:
        log.info("contacts per frame: %s vertices", ", ".join(str(c) for c in out.sum(axis=1)))
    return out
