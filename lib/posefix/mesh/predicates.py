"""Exact orientation predicates on float64 input.

Each predicate first evaluates the determinant in floating point together with Shewchuk's
forward error bound ("Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
Predicates", 1997, bound ``o3derrboundA``). Where the bound cannot certify
the sign (nearly or exactly degenerate input), the determinant is recomputed exactly in integer
arithmetic (:func:`exact_integers`). The returned signs are
therefore exact for every finite float64 input (barring underflow below ~1e-150).
"""

import numpy as np

_EPS = 2.0 ** -53
_O3D_ERRBOUND_A = (7.0 + 56.0 * _EPS) * _EPS


def orient3d(a, b, c, d):
    """Exact sign of the orientation of four points.

    Parameters
    ----------
    a, b, c, d : (k, 3) float
        Points; rows are evaluated independently.

    Returns
    -------
    (k,) int8
        ``sign(det[a - d, b - d, c - d])``: positive when ``d`` lies below the plane through
        ``a, b, c`` (seen from the side where ``a, b, c`` appear counterclockwise), zero when the
        four points are coplanar.
    """
    ad, bd, cd = a - d, b - d, c - d
    bxcy = bd[:, 0] * cd[:, 1]
    cxby = cd[:, 0] * bd[:, 1]
    cxay = cd[:, 0] * ad[:, 1]
    axcy = ad[:, 0] * cd[:, 1]
    axby = ad[:, 0] * bd[:, 1]
    bxay = bd[:, 0] * ad[:, 1]
    det = ad[:, 2] * (bxcy - cxby) + bd[:, 2] * (cxay - axcy) + cd[:, 2] * (axby - bxay)
    permanent = ((np.abs(bxcy) + np.abs(cxby)) * np.abs(ad[:, 2])
                 + (np.abs(cxay) + np.abs(axcy)) * np.abs(bd[:, 2])
                 + (np.abs(axby) + np.abs(bxay)) * np.abs(cd[:, 2]))
    sign = np.sign(det).astype(np.int8)
    unsure = np.flatnonzero(np.abs(det) <= _O3D_ERRBOUND_A * permanent)
    for i in unsure:
        sign[i] = orient3d_exact(a[i], b[i], c[i], d[i])
    return sign


def plane_coefficients(a, b, c):
    """Per-triangle part of :func:`orient3d`, computed once for many :func:`orient3d_plane` queries.

    Parameters
    ----------
    a, b, c : (k, 3) float
        Triangle vertices.

    Returns
    -------
    normal, weight : (k, 3) float
        ``normal`` is ``(b - a) x (c - a)`` evaluated in floating point (each component a difference
        of two products); ``weight`` holds the sums of the two products' magnitudes, the triangle's
        share of the error bound.
    """
    u, v = b - a, c - a
    products = [(u[:, 1] * v[:, 2], u[:, 2] * v[:, 1]), (u[:, 2] * v[:, 0], u[:, 0] * v[:, 2]),
                (u[:, 0] * v[:, 1], u[:, 1] * v[:, 0])]
    normal = np.stack([p - q for p, q in products], 1)
    weight = np.stack([np.abs(p) + np.abs(q) for p, q in products], 1)
    return normal, weight


def orient3d_plane(a, b, c, d, normal, weight):
    """:func:`orient3d` of ``a, b, c, d`` from the precomputed ``plane_coefficients(a, b, c)``.

    Parameters
    ----------
    a, b, c, d : (k, 3) float
    normal, weight : (k, 3) float
        ``plane_coefficients(a, b, c)``, row for row.

    Returns
    -------
    (k,) int8
        Exactly ``orient3d(a, b, c, d)``: ``det[a - d, b - d, c - d] = -(d - a) . ((b - a) x (c - a))``,
        and the floating-point value of the right-hand side is the same cofactor expansion of a
        determinant of rounded differences as :func:`orient3d`'s, so Shewchuk's bound ``o3derrboundA``
        times its permanent ``|d - a| . weight`` certifies its sign; the rest is decided exactly.
    """
    da = d - a
    det = da[:, 0] * normal[:, 0] + da[:, 1] * normal[:, 1] + da[:, 2] * normal[:, 2]
    permanent = np.abs(da[:, 0]) * weight[:, 0] + np.abs(da[:, 1]) * weight[:, 1] + np.abs(da[:, 2]) * weight[:, 2]
    sign = -np.sign(det).astype(np.int8)
    unsure = np.flatnonzero(np.abs(det) <= _O3D_ERRBOUND_A * permanent)
    for i in unsure:
        sign[i] = orient3d_exact(a[i], b[i], c[i], d[i])
    return sign


def orient3d_exact(a, b, c, d):
    """Sign of ``det[a - d, b - d, c - d]`` in exact arithmetic, for single float points."""
    return orient3d_int(*exact_integers(a, b, c, d))


def orient3d_int(a, b, c, d):
    """:func:`orient3d` sign for points given as exact Python integers (or Fractions)."""
    ad = [a[i] - d[i] for i in range(3)]
    bd = [b[i] - d[i] for i in range(3)]
    cd = [c[i] - d[i] for i in range(3)]
    det = (ad[2] * (bd[0] * cd[1] - cd[0] * bd[1])
           + bd[2] * (cd[0] * ad[1] - ad[0] * cd[1])
           + cd[2] * (ad[0] * bd[1] - bd[0] * ad[1]))
    return (det > 0) - (det < 0)


def orient2d_int(a, b, c):
    """Sign of ``det[a - c, b - c]`` for exact 2D points: positive when ``a, b, c`` turn counterclockwise."""
    det = (a[0] - c[0]) * (b[1] - c[1]) - (a[1] - c[1]) * (b[0] - c[0])
    return (det > 0) - (det < 0)


def exact_integers(*points):
    """Scale float points by one common power of two into exact Python integers.

    Every finite float64 is ``num / 2**k``; multiplying all coordinates by the largest ``2**k``
    makes them integers without rounding, and orientation signs are invariant under a common
    positive scale. Returns a list of lists of ints, one per point.
    """
    ratios = [[float(x).as_integer_ratio() for x in p] for p in points]
    shift = max(den.bit_length() for p in ratios for _, den in p) - 1
    return [[num << (shift - den.bit_length() + 1) for num, den in p] for p in ratios]
