"""A coarse tet mesh of a surface (S4 §2.1, §2.3.1): quadric decimation, then a Delaunay tetrahedralization.

The tets need not conform to the surface (it is carried by the tets, not rebuilt from them): the decimated
surface's vertices and a grid of interior points (spacing: the decimated mesh's mean edge length) are
tetrahedralized by Qhull, and the tets whose centroid is inside the *original* surface by the generalized
winding number are kept. That is robust to self-intersections, holes and non-manifold edges (the shared
references have all three) and deterministic (a fixed seed jitters the grid off Qhull's degenerate cases).
The largest connected set of tets is kept.
"""

import logging

import numpy as np
from scipy.sparse.csgraph import connected_components
from scipy.spatial import Delaunay, cKDTree

from posefix.mesh.winding import fast_winding_numbers
from posefix.volumetric.operators import tet_adjacency, tet_volumes

log = logging.getLogger(__name__)


def decimated_surface(V, F, surface_vertices):
    """Quadric edge collapse (pymeshlab) to about ``surface_vertices`` vertices: (V (k, 3), F (f, 3))."""
    import pymeshlab  # heavy: loaded only here

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(V, dtype=np.float64), face_matrix=np.asarray(F, np.int32)))
    if len(V) > surface_vertices:
        ms.meshing_decimation_quadric_edge_collapse(targetfacenum=int(2 * surface_vertices), preservenormal=True)
    ms.meshing_remove_unreferenced_vertices()
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), dtype=np.float64), np.asarray(m.face_matrix(), dtype=np.int64)


def interior_grid(V, F, S, spacing, seed=0):
    """Jittered grid points (k, 3) inside ``(V, F)`` (winding number >= 0.5), at least half a spacing from ``S``."""
    lo, hi = S.min(axis=0), S.max(axis=0)
    counts = np.floor((hi - lo) / spacing).astype(int) + 1
    offset = lo + 0.5 * ((hi - lo) - (counts - 1) * spacing)
    grid = np.stack(np.meshgrid(*[np.arange(c) for c in counts], indexing="ij"), axis=-1).reshape(-1, 3)
    points = offset + spacing * grid + np.random.default_rng(seed).uniform(-0.1, 0.1, (len(grid), 3)) * spacing
    points = points[fast_winding_numbers(V, F, points) >= 0.5]
    clear = cKDTree(S).query(points)[0] >= 0.5 * spacing
    return points[clear]


def tet_mesh(V, F, surface_vertices=2500):
    """Coarse tet mesh of the surface ``(V, F)``.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    surface_vertices : int
        Vertices of the decimated surface (S4 used 1-4k tet-mesh vertices).

    Returns
    -------
    X : (k, 3) float
        Tet-mesh vertices: decimated surface vertices, then interior points.
    T : (t, 4) int64
        Positively oriented tets, one connected set.
    """
    S, G = decimated_surface(V, F, surface_vertices)
    spacing = float(np.linalg.norm(S[G] - S[np.roll(G, 1, axis=1)], axis=2).mean())
    X = np.vstack([S, interior_grid(V, F, S, spacing)])
    T = Delaunay(X).simplices.astype(np.int64)
    T = T[fast_winding_numbers(V, F, X[T].mean(axis=1)) >= 0.5]
    volumes = tet_volumes(X, T)
    T = T[np.abs(volumes) > 1e-12 * spacing ** 3]
    flip = tet_volumes(X, T) < 0
    T[flip] = T[flip][:, [0, 2, 1, 3]]
    _, label = connected_components(tet_adjacency(T), directed=False)
    T = T[label == np.argmax(np.bincount(label))]
    used = np.unique(T)
    index = np.full(len(X), -1)
    index[used] = np.arange(len(used))
    log.info("tet mesh: %d surface vertices (decimated), %d vertices, %d tets", len(S), len(used), len(T))
    return X[used], index[T]
