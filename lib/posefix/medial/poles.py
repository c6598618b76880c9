"""Inner Voronoi poles (Amenta, Bern, Kamvysselis 1998): the medial-ball centres of the paper, §2.

The Voronoi cell of a dense surface sample is long and thin along the normal; its vertex farthest
from the sample on the inner side approximates the centre of the inner medial ball touching the
surface there. The Voronoi diagram is Qhull's (``scipy.spatial.Voronoi``), as in the paper.
"""

import itertools
import logging
import time

import numpy as np
from scipy.spatial import Voronoi

log = logging.getLogger(__name__)


def inner_poles(V, N):
    """Inner Voronoi pole of every vertex.

    Parameters
    ----------
    V : (n, 3) float
        Surface samples (mesh vertices), n >= 5 and not all coplanar.
    N : (n, 3) float
        Outward unit normals at ``V`` (zero rows get no pole).

    Returns
    -------
    S : (n, 3) float
        For each vertex ``x_i``, the vertex ``v`` of its Voronoi cell farthest from ``x_i`` among
        the finite ones on the inner side, ``(v - x_i) . n_i < 0``; NaN where none is found.
    found : (n,) bool
        False where the cell has no finite vertex on the inner side, the normal is zero, or Qhull
        gave the point no cell. Exact duplicate points share one cell (the same region in
        ``scipy``): each copy gets the pole of that cell on the side of its own normal.
    """
    start = time.perf_counter()
    V = np.asarray(V, dtype=np.float64)
    vor = Voronoi(V)
    point, vertex = _cell_vertices(vor)
    offset = vor.vertices[vertex] - V[point]
    inner = np.einsum("ij,ij->i", offset, N[point]) < 0
    point, vertex, dist = point[inner], vertex[inner], np.einsum("ij,ij->i", offset[inner], offset[inner])
    order = np.lexsort((vertex, -dist, point))  # per point: farthest first, ties to the lowest vertex
    point, vertex = point[order], vertex[order]
    first = np.ones(len(point), dtype=bool)
    first[1:] = point[1:] != point[:-1]
    S = np.full((len(V), 3), np.nan)
    S[point[first]] = vor.vertices[vertex[first]]
    found = np.zeros(len(V), dtype=bool)
    found[point[first]] = True
    log.info("inner Voronoi poles of %d points: %d found, %.2f s", len(V), found.sum(), time.perf_counter() - start)
    return S, found


def _cell_vertices(vor):
    """The finite Voronoi vertices of every input point's cell as flat pairs.

    Returns
    -------
    point, vertex : (e,) int64
        Entry ``j`` says that Voronoi vertex ``vertex[j]`` is a corner of the cell of ``point[j]``
        (the vertex at infinity, ``-1``, left out).
    """
    lengths = np.fromiter(map(len, vor.regions), dtype=np.int64, count=len(vor.regions))
    flat = np.fromiter(itertools.chain.from_iterable(vor.regions), dtype=np.int64, count=int(lengths.sum()))
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    region = np.asarray(vor.point_region, dtype=np.int64)
    has = region >= 0
    count = np.where(has, lengths[np.where(has, region, 0)], 0)
    point = np.repeat(np.arange(len(region)), count)
    within = np.arange(len(point)) - np.repeat(np.cumsum(count) - count, count)
    vertex = flat[starts[region[point]] + within]
    keep = vertex >= 0
    return point[keep], vertex[keep]
