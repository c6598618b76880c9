"""Exact detection of self-intersecting triangles.

Two faces *intersect* when their closed triangles share at least one point (touching counts,
as in CGAL's ``do_intersect``). Pairs of faces that share a vertex are never tested or reported
(the convention of S0 and of the counts in ``../shared/data/SOURCES.md``).

Pipeline: a :mod:`posefix.mesh.bvh` box tree gives the candidate pairs whose bounding boxes overlap;
pairs sharing a vertex are dropped (nine vectorized comparisons of vertex ids); the rest go through a
vectorized test built only from exact :func:`posefix.mesh.predicates.orient3d` signs, the plane-side
ones through :func:`~posefix.mesh.predicates.orient3d_plane` from per-face plane coefficients
computed once per call, one triangle's plane first (which rejects most pairs) and the other's only
for the pairs left:

* if all vertices of one triangle lie strictly on one side of the other's plane, no intersection;
* otherwise (non-coplanar, non-degenerate) the triangles intersect iff an edge of one meets the
  other closed triangle, because the endpoints of the intersection segment lie on edges;
* coplanar pairs, zero-area triangles and edges lying in the other triangle's plane (rare) are
  decided one by one in exact integer arithmetic (:func:`triangles_intersect_exact`).

Only the (few) intersecting pairs are sorted. Every sign is exact, so the result does not depend on
the tree or on the order in which pairs are tested.
"""

import numpy as np

from posefix.mesh.bvh import build_box_tree, self_overlapping_pairs
from posefix.mesh.predicates import (exact_integers, orient2d_int, orient3d, orient3d_int, orient3d_plane,
                                     plane_coefficients)

_EDGES = ((0, 1), (1, 2), (2, 0))
_CHUNK = 200_000


def self_intersecting_pairs(V, F):
    """Pairs of faces that intersect and share no vertex.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int

    Returns
    -------
    (k, 2) int64
        Face index pairs ``(f, g)``, ``f < g``, sorted lexicographically.
    """
    T = np.asarray(V, dtype=np.float64)[F]
    planes = plane_coefficients(T[:, 0], T[:, 1], T[:, 2])
    P = candidate_pairs(V, F)
    hits = np.zeros(len(P), dtype=bool)
    for start in range(0, len(P), _CHUNK):
        f, g = P[start:start + _CHUNK, 0], P[start:start + _CHUNK, 1]
        hits[start:start + _CHUNK] = _pairs_intersect(np.take(T, f, axis=0), np.take(T, g, axis=0),
                                                      [np.take(x, f, axis=0) for x in planes],
                                                      [np.take(x, g, axis=0) for x in planes])
    P = P[hits]
    return P[np.lexsort((P[:, 1], P[:, 0]))]


def candidate_pairs(V, F):
    """Face pairs with overlapping bounding boxes that share no vertex.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int

    Returns
    -------
    (k, 2) int64
        Face pairs ``(f, g)``, ``f < g``, in the box tree's deterministic order (not sorted).
    """
    V, F = np.asarray(V, dtype=np.float64), np.asarray(F)
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    P = self_overlapping_pairs(build_box_tree(np.minimum(np.minimum(A, B), C), np.maximum(np.maximum(A, B), C)))
    Ft = np.ascontiguousarray(F.T, dtype=np.int32 if len(V) < 2**31 else np.int64)  # (3, m), narrow
    Fa, Fb = np.take(Ft, P[:, 0], axis=1), np.take(Ft, P[:, 1], axis=1)
    shared = Fa[0] == Fb[0]
    for i in range(3):
        for j in range(3):
            if i or j:
                shared |= Fa[i] == Fb[j]
    return P[~shared]


def intersecting_faces(pairs, m):
    """Mask of faces that appear in at least one pair, (m,) bool."""
    mask = np.zeros(m, dtype=bool)
    mask[np.asarray(pairs, dtype=np.int64).ravel()] = True
    return mask


def new_pairs(pairs, reference_pairs):
    """Rows of ``pairs`` (k, 2) that are not in ``reference_pairs``; both sorted with ``f < g``."""
    if len(pairs) == 0 or len(reference_pairs) == 0:
        return pairs
    width = np.int64(max(pairs.max(), reference_pairs.max()) + 1)
    return pairs[~np.isin(pairs[:, 0] * width + pairs[:, 1], reference_pairs[:, 0] * width + reference_pairs[:, 1])]


def triangle_pairs_intersect(A, B):
    """Exact closed intersection test for paired triangles.

    Parameters
    ----------
    A, B : (k, 3, 3) float
        Triangle ``i`` is ``A[i]`` (three vertices, rows), paired with ``B[i]``.

    Returns
    -------
    (k,) bool
    """
    A, B = np.asarray(A, dtype=np.float64), np.asarray(B, dtype=np.float64)
    return _pairs_intersect(A, B, plane_coefficients(A[:, 0], A[:, 1], A[:, 2]),
                            plane_coefficients(B[:, 0], B[:, 1], B[:, 2]))


def _pairs_intersect(A, B, plane_a, plane_b):
    """:func:`triangle_pairs_intersect` given each triangle's ``plane_coefficients`` (two (k, 3) arrays)."""
    hit = np.zeros(len(A), dtype=bool)
    dB = _plane_sides(A, plane_a, B)
    maybe = np.flatnonzero(~_one_side(dB))
    A, B, dB = A[maybe], B[maybe], dB[:, maybe]
    dA = _plane_sides(B, [x[maybe] for x in plane_b], A)
    hit[maybe] = _straddling_pairs_intersect(A, B, dA, dB)
    return hit


def _plane_sides(X, plane, Y):
    """Exact ``orient3d(X[:, 0], X[:, 1], X[:, 2], Y[:, i])`` for i = 0, 1, 2, (3, k) int8."""
    return np.stack([orient3d_plane(X[:, 0], X[:, 1], X[:, 2], Y[:, i], *plane) for i in range(3)])


def _one_side(d):
    """Columns of plane-side signs (3, k) all strictly positive or all strictly negative, (k,) bool."""
    total = d[0] + d[1] + d[2]
    return (total == 3) | (total == -3)


def _two_zeros(d):
    """Columns of plane-side signs (3, k) with at least two zeros, i.e. an edge in the plane, (k,) bool."""
    zero = d == 0
    return (zero[0] & zero[1]) | (zero[1] & zero[2]) | (zero[2] & zero[0])


def _straddling_pairs_intersect(A, B, dA, dB):
    """Exact test of paired triangles ``A, B`` (k, 3, 3) where ``B`` does not lie strictly on one side of ``A``.

    ``dA`` (3, k) are the exact sides of ``A``'s vertices against ``B``'s plane, ``dB`` of ``B``'s
    against ``A``'s; returns (k,) bool. Pairs with an edge in the other's plane (which includes
    coplanar pairs and zero-area triangles) go to :func:`triangles_intersect_exact`.
    """
    separated = _one_side(dA)
    special = ~separated & (_two_zeros(dA) | _two_zeros(dB))
    hit = np.zeros(len(A), dtype=bool)
    todo = np.flatnonzero(~separated & ~special)
    for X, Y, dX in ((A, B, dA), (B, A, dB)):
        for i, j in _EDGES:
            idx = todo[(dX[i, todo] * dX[j, todo] <= 0) & ~hit[todo]]
            hit[idx] = _line_through_triangle(X[idx, i], X[idx, j], Y[idx])
    for i in np.flatnonzero(special):
        hit[i] = triangles_intersect_exact(A[i], B[i])
    return hit


def _line_through_triangle(p, q, T):
    """Whether the line through ``p, q`` meets the closed triangle ``T``, (k,) bool.

    Valid when the line is not parallel to the triangle's plane (the caller guarantees it crosses it).
    """
    o = [orient3d(p, q, T[:, i], T[:, j]) for i, j in _EDGES]
    return ~(((o[0] > 0) | (o[1] > 0) | (o[2] > 0)) & ((o[0] < 0) | (o[1] < 0) | (o[2] < 0)))


# ---------------------------------------------------------------- exact integer fallback

def triangles_intersect_exact(a, b):
    """Exact closed intersection test of two triangles, any configuration.

    Parameters
    ----------
    a, b : (3, 3) float
        Vertices as rows.

    Returns
    -------
    bool
        Handles coplanar triangles, edges lying in the other plane, and zero-area triangles
        (treated as the segment or point they span); two zero-area triangles are compared as
        their spanning segments.
    """
    pts = exact_integers(*a, *b)
    a, b = pts[:3], pts[3:]
    if _degenerate(a) and _degenerate(b):
        return _segments_intersect_3d(_span(a), _span(b))
    if _degenerate(a):
        a, b = b, a
    if _degenerate(b):
        p, q = _span(b)
        return _segment_triangle(p, q, a)
    dB = [orient3d_int(a[0], a[1], a[2], p) for p in b]
    dA = [orient3d_int(b[0], b[1], b[2], p) for p in a]
    if abs(sum(dB)) == 3 or abs(sum(dA)) == 3:
        return False
    if all(s == 0 for s in dB):
        return _coplanar_triangles(a, b)
    return any(_segment_triangle(X[i], X[j], Y) for X, Y in ((a, b), (b, a)) for i, j in _EDGES)


def _segment_triangle(p, q, T):
    """Closed segment ``pq`` against a non-degenerate closed triangle ``T`` (exact)."""
    sp, sq = orient3d_int(T[0], T[1], T[2], p), orient3d_int(T[0], T[1], T[2], q)
    if sp * sq > 0:
        return False
    if sp == 0 and sq == 0:
        axis = _drop_axis(T)
        p2, q2, T2 = _project(p, axis), _project(q, axis), [_project(t, axis) for t in T]
        return (_point_in_triangle_2d(p2, T2) or _point_in_triangle_2d(q2, T2)
                or any(_segments_intersect_2d(p2, q2, T2[i], T2[j]) for i, j in _EDGES))
    o = [orient3d_int(p, q, T[i], T[j]) for i, j in _EDGES]
    return all(s >= 0 for s in o) or all(s <= 0 for s in o)


def _coplanar_triangles(a, b):
    axis = _drop_axis(a)
    a2, b2 = [_project(p, axis) for p in a], [_project(p, axis) for p in b]
    if any(_point_in_triangle_2d(p, b2) for p in a2) or any(_point_in_triangle_2d(p, a2) for p in b2):
        return True
    return any(_segments_intersect_2d(a2[i], a2[j], b2[k], b2[l]) for i, j in _EDGES for k, l in _EDGES)


def _point_in_triangle_2d(p, T):
    o = [orient2d_int(T[i], T[j], p) for i, j in _EDGES]
    return all(s >= 0 for s in o) or all(s <= 0 for s in o)


def _segments_intersect_2d(p, q, r, s):
    """Closed 2D segments ``pq`` and ``rs`` (either may be a point)."""
    o1, o2 = orient2d_int(p, q, r), orient2d_int(p, q, s)
    o3, o4 = orient2d_int(r, s, p), orient2d_int(r, s, q)
    if o1 * o2 < 0 and o3 * o4 < 0:
        return True
    return ((o1 == 0 and _on_segment(p, q, r)) or (o2 == 0 and _on_segment(p, q, s))
            or (o3 == 0 and _on_segment(r, s, p)) or (o4 == 0 and _on_segment(r, s, q)))


def _on_segment(p, q, x):
    """For ``x`` collinear with ``p, q``: whether it lies in their closed bounding box."""
    return all(min(p[i], q[i]) <= x[i] <= max(p[i], q[i]) for i in range(len(x)))


def _segments_intersect_3d(s, t):
    (p, q), (r, u) = s, t
    if orient3d_int(p, q, r, u) != 0:
        return False
    pts = [p, q, r, u]
    for axis in range(3):
        proj = [_project(x, axis) for x in pts]
        # a projection along an axis is injective on the common plane/line unless it collapses it
        if _injective(proj, pts):
            return _segments_intersect_2d(*proj)
    return p == r


def _injective(proj, pts):
    """Whether distinct 3D points stay distinct and the configuration keeps its rank in 2D."""
    rank3 = _rank(pts)
    rank2 = _rank([x + [0] for x in proj])
    return rank2 == rank3


def _rank(pts):
    vecs = [[pts[i][k] - pts[0][k] for k in range(3)] for i in range(1, len(pts))]
    nonzero = [v for v in vecs if any(v)]
    if not nonzero:
        return 0
    v0 = nonzero[0]
    if all(not any(_cross(v0, v)) for v in nonzero):
        return 1
    return 2


def _cross(u, v):
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


def _degenerate(T):
    return not any(_cross([T[1][k] - T[0][k] for k in range(3)], [T[2][k] - T[0][k] for k in range(3)]))


def _span(T):
    """The two vertices of a zero-area triangle that span it."""
    pairs = [(T[i], T[j]) for i, j in _EDGES]
    return max(pairs, key=lambda pq: sum((pq[0][k] - pq[1][k]) ** 2 for k in range(3)))


def _drop_axis(T):
    n = _cross([T[1][k] - T[0][k] for k in range(3)], [T[2][k] - T[0][k] for k in range(3)])
    return max(range(3), key=lambda k: abs(n[k]))


def _project(p, axis):
    return [p[k] for k in range(3) if k != axis]
