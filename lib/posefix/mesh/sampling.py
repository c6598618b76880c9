"""Well-spread vertex samples of a mesh: farthest-point sampling in the geodesic (edge-path) distance."""

import numpy as np
from scipy.sparse.csgraph import dijkstra

from posefix.mesh.contacts import edge_graph


def geodesic_farthest_points(V, F, count):
    """``count`` vertices, each the farthest along the surface's edges from those before it, (count,) int64.

    Starts from the vertex farthest from the centroid; deterministic (ties: lowest index). On a body the
    samples go to the tips of the limbs first, then split the limbs and the torso evenly, where Euclidean
    samples would skip one of two feet that stand close together (simulated motion-capture markers).

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    count : int
        At most the number of vertices reachable from the first one.

    Examples
    --------
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]); F = np.array([[0, 1, 2], [1, 2, 3]])
    >>> geodesic_farthest_points(V, F, 2).tolist()
    [0, 3]
    """
    graph = edge_graph(V, F)
    chosen = [int(np.argmax(np.linalg.norm(V - V.mean(axis=0), axis=1)))]
    distance = dijkstra(graph, indices=chosen[0])
    while len(chosen) < count:
        chosen.append(int(np.argmax(np.where(np.isfinite(distance), distance, -1.0))))
        distance = np.minimum(distance, dijkstra(graph, indices=chosen[-1]))
    return np.array(chosen, dtype=np.int64)
