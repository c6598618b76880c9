"""Near contacts: vertices that come close to a geodesically distant part of the surface.

A vertex ``v`` is *in contact* in a frame when some face lies within Euclidean distance
``distance`` of it there, while that face is *non-neighbouring*: at least ``radius`` away from ``v``
along the edges of the **reference** mesh (an upper bound of the geodesic distance). Edge-path
distance is used rather than a k-ring because edge lengths vary by orders of magnitude on real
meshes (1e-4 d to 0.056 d on the lion).

To avoid testing the millions of vertex-face pairs that are close because they are neighbours, the
reference is cut into geodesic patches of radius about ``radius / 4``. By the triangle inequality
over the patch seeds, a pair of patches is *near* (every vertex pair within ``radius``: skipped),
*far* (every pair at least ``radius`` apart: no further check) or *ambiguous* (the vertex-face
pairs found there are checked exactly with a Dijkstra search from their vertices). Only patch
pairs whose boxes come within ``distance`` in a frame are looked at, so the cost follows the
number of real contacts, not the mesh density.
"""

import logging

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from posefix.mesh.bvh import build_box_tree, cross_overlapping_pairs
from posefix.mesh.geometry import point_triangle_distance
from posefix.mesh.topology import edges

log = logging.getLogger(__name__)

_PATCH_FRACTION = 0.1

_CHUNK = 1 << 20
"""Vertex-face pairs looked at a time (about 200 bytes each): the pairs of close patches grow with the contacts
(kids-0001, 60k vertices, 11 frames: a 13.6 GB peak when every frame's were held at once, 1.0 GB in chunks)."""


def edge_graph(V, F):
    """Symmetric sparse (n, n) matrix of edge lengths of a mesh."""
    E = edges(F)
    w = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    G = sp.coo_matrix((w, (E[:, 0], E[:, 1])), shape=(len(V), len(V)))
    return (G + G.T).tocsr()


NEAR, AMBIGUOUS, FAR = 0, 1, 2


def geodesic_patches(graph, V_ref, radius):
    """Cut the reference into geodesic patches and classify every pair of patches.

    Parameters
    ----------
    graph : (n, n) sparse
        Edge lengths of the reference (:func:`edge_graph`).
    V_ref : (n, 3) float
    radius : float

    Returns
    -------
    patch : (n,) int64
        Patch of every vertex.
    status : (k, k) int8
        ``NEAR`` (all vertex pairs within ``radius`` along the edges), ``FAR`` (all at least
        ``radius`` apart) or ``AMBIGUOUS``.
    to_seed : (n,) float
        Edge-path distance of every vertex to its patch seed.
    between : (k, k) float
        Edge-path distances between seeds (inf beyond ``radius`` plus twice the largest patch radius).
    """
    seeds = _seeds(V_ref, _PATCH_FRACTION * radius)
    dist, _, source = dijkstra(graph, directed=False, indices=seeds, min_only=True, return_predecessors=True)
    patch = np.searchsorted(seeds, source)
    unreachable = source < 0  # vertices on no face: patches of their own
    if unreachable.any():
        extra = np.flatnonzero(unreachable)
        seeds = np.concatenate([seeds, extra])
        patch[extra] = len(seeds) - len(extra) + np.arange(len(extra))
        dist[extra] = 0.0
    rad = np.zeros(len(seeds))
    np.maximum.at(rad, patch, dist)
    limit = radius + 2 * rad.max()
    between = np.concatenate([dijkstra(graph, directed=False, indices=seeds[i:i + 64], limit=limit)[:, seeds]
                              for i in range(0, len(seeds), 64)])
    spread = rad[:, None] + rad[None, :]
    status = np.full(between.shape, AMBIGUOUS, dtype=np.int8)
    status[between + spread < radius] = NEAR
    status[between > radius + spread] = FAR
    return patch, status, dist, between


def _seeds(V, spacing):
    """Vertex indices, sorted, such that every vertex is within ``spacing`` (Euclidean) of one."""
    chosen = [0]
    dist = np.linalg.norm(V - V[0], axis=1)
    while dist.max() > spacing:
        i = int(np.argmax(dist))
        chosen.append(i)
        dist = np.minimum(dist, np.linalg.norm(V - V[i], axis=1))
    return np.array(sorted(chosen), dtype=np.int64)


def contact_vertices(frames, F, V_ref, distance, radius):
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
    patch, status, to_seed, between = geodesic_patches(graph, V_ref, radius)
    k = len(status)
    vert_order = np.argsort(patch, kind="stable")
    vert_start = np.searchsorted(patch[vert_order], np.arange(k + 1))
    face_patch = patch[F[:, 0]]
    face_order = np.argsort(face_patch, kind="stable")
    face_start = np.searchsorted(face_patch[face_order], np.arange(k + 1))
    face_status = status[:, patch[F[:, 0]]]  # (k, m): the nearest of a face's vertex patches
    for corner in (1, 2):
        np.minimum(face_status, status[:, patch[F[:, corner]]], out=face_status)
    groups = (vert_order, vert_start, face_order, face_start)
    patches = (patch, status, face_status, to_seed, between, radius)
    out = np.zeros(frames.shape[:2], dtype=bool)
    unsure = []
    for frame, V in enumerate(frames):
        for vv, ff in _close_pairs(V, F, distance, groups, patches):
            far = face_status[patch[vv], ff] == FAR
            rest = np.flatnonzero(~far)
            near, sure_far = _vertex_bounds(np.stack([vv[rest], ff[rest]], 1), F, patch, to_seed, between, radius)
            far[rest[sure_far]] = True
            out[frame, vv[far]] = True
            rest = rest[~near & ~sure_far]
            unsure.append(np.stack([np.full(len(rest), frame), vv[rest], ff[rest]], 1))
    unsure = np.concatenate(unsure) if unsure else np.zeros((0, 3), dtype=np.int64)
    unsure = unsure[~out[unsure[:, 0], unsure[:, 1]]]  # a vertex already in contact needs no search
    far = non_neighbouring(unsure[:, 1:], F, graph, radius, V_ref)
    out[unsure[far, 0], unsure[far, 1]] = True
    log.info("contacts per frame (%d patches, %d pairs checked exactly): %s vertices", k, len(unsure),
             ", ".join(str(c) for c in out.sum(axis=1)))
    return out


def _close_pairs(V, F, distance, groups, patches):
    """Yield, about :data:`_CHUNK` pairs at a time, (vertices (p,), faces (p,)) int64: the vertices of ``V`` (n, 3)
    closer than ``distance`` to a face of another patch that is neither NEAR theirs nor surely near them by
    :func:`_vertex_bounds`. ``groups``: (vertex order, vertex starts, face order, face starts) of the patches;
    ``patches``: (patch of each vertex (n,), patch status (k, k), face status (k, m), distance of each vertex to its
    patch's seed (n,), distances between seeds (k, k), the neighbourhood radius) (:func:`geodesic_patches`). Within
    each pair of patches whose boxes come that close, a box tree of the one's vertices against one of the other's
    faces finds the pairs to measure: their count grows with the contacts, not with the product of the patches'
    sizes."""
    vert_order, vert_start, face_order, face_start = groups
    patch, status = patches[:2]
    with_faces = np.flatnonzero(face_start[1:] > face_start[:-1])
    T = V[F]
    t_lo, t_hi = T.min(axis=1), T.max(axis=1)
    v_lo, v_hi = _group_boxes(V[vert_order], V[vert_order], vert_start)
    f_lo, f_hi = _group_boxes(t_lo[face_order], t_hi[face_order], face_start)
    pairs = cross_overlapping_pairs(build_box_tree(v_lo - distance, v_hi + distance),
                                    build_box_tree(f_lo[with_faces], f_hi[with_faces]))
    a, b = pairs[:, 0], with_faces[pairs[:, 1]]
    a, b = a[status[a, b] != NEAR], b[status[a, b] != NEAR]
    trees, found, count = {}, [], 0
    for i, (pa, pb) in enumerate(zip(a, b)):
        verts, faces = vert_order[vert_start[pa]:vert_start[pa + 1]], face_order[face_start[pb]:face_start[pb + 1]]
        if ("v", pa) not in trees:
            trees["v", pa] = build_box_tree(V[verts] - distance, V[verts] + distance)
        if ("f", pb) not in trees:
            trees["f", pb] = build_box_tree(t_lo[faces], t_hi[faces])
        close = cross_overlapping_pairs(trees["v", pa], trees["f", pb])
        found.append((verts[close[:, 0]], faces[close[:, 1]]))
        count += len(close)
        if count >= _CHUNK or i == len(a) - 1:
            yield _measured(V, F, distance, found, patches)
            found, count = [], 0


def _measured(V, F, distance, found, patches):
    """The pairs of ``found`` (list of (vertices, faces)) whose face is neither NEAR the vertex's patch nor surely
    near the vertex by :func:`_vertex_bounds` (both pair by pair, cheaper than the distance), and closer than
    ``distance`` to it: (vertices (p,), faces (p,)). ``patches``: as :func:`_close_pairs`."""
    patch, _, face_status, to_seed, between, radius = patches
    vv, ff = (np.concatenate(x) for x in zip(*found))
    keep = face_status[patch[vv], ff] != NEAR
    vv, ff = vv[keep], ff[keep]
    near, _ = _vertex_bounds(np.stack([vv, ff], 1), F, patch, to_seed, between, radius)
    vv, ff = vv[~near], ff[~near]
    T = V[F[ff]]
    hit = point_triangle_distance(V[vv], T[:, 0], T[:, 1], T[:, 2]) < distance
    return vv[hit], ff[hit]


def _vertex_bounds(pairs, F, patch, to_seed, between, radius):
    """Decide vertex-face pairs by triangle-inequality bounds through the patch seeds.

    Returns two (p,) bool masks: surely near (some face vertex within ``radius``) and surely far
    (all face vertices at least ``radius`` away); the rest needs an exact search.
    """
    v, W = pairs[:, 0], F[pairs[:, 1]]
    via = between[patch[v][:, None], patch[W]]
    spread = to_seed[v][:, None] + to_seed[W]
    return (via + spread < radius).any(axis=1), (via - spread >= radius).all(axis=1)


def non_neighbouring(pairs, F, graph, radius, V, rows=128):
    """Mask of vertex-face pairs whose face is at least ``radius`` away along ``graph``.

    The sources go in spatial order, ``rows`` at a time, and each chunk's Dijkstra runs on the vertices within
    ``radius`` of the chunk's box only: a path shorter than ``radius`` along the edges stays within that distance
    in space, so the distances below ``radius`` are the whole graph's (kids at 239k vertices, 8.0 M pairs: the same
    classify.h5, its contacts in 298 s instead of 328 s; each source's ball of 0.1 d still holds thousands of
    vertices, whose distances are what costs).

    Parameters
    ----------
    pairs : (p, 2) int
        Vertex, face.
    F : (m, 3) int
    graph : (n, n) sparse
        Edge lengths (:func:`edge_graph`).
    radius : float
    V : (n, 3) float
        The graph's vertex positions (its edge lengths are their distances).
    rows : int
        Dijkstra sources per chunk.

    Returns
    -------
    (p,) bool
    """
    keep = np.ones(len(pairs), dtype=bool)
    sources = np.unique(pairs[:, 0])
    cells = np.floor((V[sources] - V.min(axis=0)) / radius).astype(np.int64)
    sources = sources[np.lexsort(cells.T[::-1])]  # cell by cell: a chunk's sources lie close together
    rank = np.empty(len(V), dtype=np.int64)
    rank[sources] = np.arange(len(sources))
    order = np.argsort(rank[pairs[:, 0]], kind="stable")
    starts = np.searchsorted(rank[pairs[order, 0]], np.arange(0, len(sources) + rows, rows))
    graph = sp.csr_matrix(graph)
    for c, start in enumerate(range(0, len(sources), rows)):
        chunk, mine = sources[start:start + rows], order[starts[c]:starts[c + 1]]
        lo, hi = V[chunk].min(axis=0) - radius, V[chunk].max(axis=0) + radius
        around = np.flatnonzero(((V >= lo) & (V <= hi)).all(axis=1))
        local = np.full(len(V), -1)
        local[around] = np.arange(len(around))
        dist = dijkstra(graph[around][:, around], directed=False, indices=local[chunk], limit=radius)
        dist = np.concatenate([dist, np.full((len(chunk), 1), np.inf)], axis=1)  # column -1: outside
        near = dist[rank[pairs[mine, 0]][:, None] - start, local[F[pairs[mine, 1]]]].min(axis=1) < radius
        keep[mine[near]] = False
    return keep


def _group_boxes(lo, hi, start):
    """Bounding boxes (k, 3) of rows grouped in consecutive runs ``start[g]:start[g+1]``.

    Empty groups get inverted boxes (``+inf`` / ``-inf``), which overlap nothing.
    """
    k = len(start) - 1
    out_lo, out_hi = np.full((k, 3), np.inf), np.full((k, 3), -np.inf)
    full = np.flatnonzero(start[1:] > start[:-1])
    if len(full):
        out_lo[full] = np.minimum.reduceat(lo, start[full], axis=0)
        out_hi[full] = np.maximum.reduceat(hi, start[full], axis=0)
    return out_lo, out_hi
