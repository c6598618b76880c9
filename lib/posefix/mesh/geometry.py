"""Per-mesh geometric quantities: bounding-box diagonal, edge lengths, face normals and areas, vertex areas."""

import numpy as np


def bbox_diagonal(V):
    """Length of the axis-aligned bounding-box diagonal.

    Parameters
    ----------
    V : (n, 3) float
        Vertex positions.

    Returns
    -------
    float
        ``||max(V) - min(V)||`` in the units of ``V``.
    """
    return float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))


def unit_scale(V):
    """The power of two that brings the bounding-box diagonal of ``V`` into [1/sqrt(2), sqrt(2)): the working unit
    of the contact solver and the finish.

    A library at 1e-30 or 1e+30 then meets the absolute constants of third-party numerics (ipctk's CCD gaps and PSD
    projection, at 1e-30: "unable to project matrix onto positive semi-definite cone") as at 1. Multiplying by a
    power of two is exact in floating point (and commutes with rounding to float32), so positions scaled back by it
    are exactly those at the working scale, scaled.

    Parameters
    ----------
    V : (n, 3) float
        The reference's positions (any length unit).

    Returns
    -------
    float
        ``2^-k``, ``k`` the integer nearest to ``log2`` of the diagonal (1 where it is 0 or not finite).

    Examples
    --------
    >>> unit_scale(np.array([[0.0, 0, 0], [3e-30, 4e-30, 0]])) * 5e-30
    0.7922816251426433
    """
    d = bbox_diagonal(V)
    return float(2.0 ** -round(np.log2(d))) if np.isfinite(d) and d > 0 else 1.0


def edge_lengths(V, E):
    """Lengths of edges ``E`` (e, 2) int of vertices ``V`` (n, 3) float, (e,) float."""
    return np.linalg.norm(V[E[:, 1]] - V[E[:, 0]], axis=1)


def face_cross(V, F):
    """Unnormalized face normals ``(v1 - v0) x (v2 - v0)``.

    Returns
    -------
    (m, 3) float
        Each row has length twice the face area and points along the right-handed normal.
    """
    v0, v1, v2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return np.cross(v1 - v0, v2 - v0)


def face_areas(V, F):
    """Triangle areas, (m,) float in squared length units."""
    return 0.5 * np.linalg.norm(face_cross(V, F), axis=1)


def vertex_areas(V, F):
    """Barycentric vertex areas: a third of the area of every incident face.

    Returns
    -------
    (n,) float
        Sums to the total surface area; zero for vertices on no face.
    """
    third = np.repeat(face_areas(V, F) / 3.0, 3)
    return np.bincount(F.ravel(), weights=third, minlength=len(V))


def vertex_normals(V, F):
    """Area-weighted unit vertex normals, (n, 3) float; zero for vertices on no face."""
    N = np.zeros((len(V), 3))
    cross = face_cross(V, F)
    for i in range(3):
        np.add.at(N, F[:, i], cross)
    length = np.linalg.norm(N, axis=1, keepdims=True)
    return N / np.where(length > 0, length, 1.0)


def point_triangle_distance(P, A, B, C):
    """Euclidean distance from points to paired closed triangles (Ericson, Real-Time Collision
    Detection, 5.1.5), vectorized.

    Parameters
    ----------
    P, A, B, C : (k, 3) float
        Point ``P[i]`` and triangle ``(A[i], B[i], C[i])``; triangles may be degenerate.

    Returns
    -------
    (k,) float
    """
    ab, ac, ap = B - A, C - A, P - A
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    bp, cp = P - B, P - C
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v_in, w_in = vb / denom, vc / denom
        closest = A + v_in[:, None] * ab + w_in[:, None] * ac
        cases = [
            (d1 <= 0) & (d2 <= 0), (d3 >= 0) & (d4 <= d3), (d6 >= 0) & (d5 <= d6),
            (vc <= 0) & (d1 >= 0) & (d3 <= 0), (vb <= 0) & (d2 >= 0) & (d6 <= 0),
            (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0),
        ]
        edge_ab = A + np.nan_to_num(d1 / (d1 - d3))[:, None] * ab
        edge_ac = A + np.nan_to_num(d2 / (d2 - d6))[:, None] * ac
        edge_bc = B + np.nan_to_num((d4 - d3) / ((d4 - d3) + (d5 - d6)))[:, None] * (C - B)
    for case, point in reversed(list(zip(cases, (A, B, C, edge_ab, edge_ac, edge_bc)))):
        closest = np.where(case[:, None], point, closest)
    dist = np.linalg.norm(P - closest, axis=1)
    degenerate = ~(denom > 0) | ~np.isfinite(dist)  # denom = |ab x ac|^2
    if degenerate.any():
        dist[degenerate] = _segment_distance_min(P[degenerate], A[degenerate], B[degenerate], C[degenerate])
    return dist


def _dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def _segment_distance_min(P, A, B, C):
    """Distance from points to the union of a triangle's three edges (for zero-area triangles)."""
    out = np.full(len(P), np.inf)
    for a, b in ((A, B), (B, C), (C, A)):
        ab = b - a
        t = np.clip(np.nan_to_num(_dot(P - a, ab) / _dot(ab, ab)), 0.0, 1.0)
        out = np.minimum(out, np.linalg.norm(P - (a + t[:, None] * ab), axis=1))
    return out
