"""Exact orientation predicates: agree with rational arithmetic where floating point fails."""

from fractions import Fraction

import numpy as np

from posefix.mesh.predicates import (exact_integers, orient2d_int, orient3d, orient3d_exact, orient3d_plane,
                                     plane_coefficients)


def _exact_sign(a, b, c, d):
    a, b, c, d = ([Fraction(float(x)) for x in p] for p in (a, b, c, d))
    m = [[a[i] - d[i] for i in range(3)], [b[i] - d[i] for i in range(3)], [c[i] - d[i] for i in range(3)]]
    det = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
           + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
    return (det > 0) - (det < 0)


def test_orient3d_basic_signs():
    a, b, c = np.array([[0.0, 0, 0]]), np.array([[1.0, 0, 0]]), np.array([[0.0, 1, 0]])
    below, above, on = np.array([[0.2, 0.2, -1.0]]), np.array([[0.2, 0.2, 1.0]]), np.array([[5.0, 7.0, 0.0]])
    assert orient3d(a, b, c, below)[0] == 1
    assert orient3d(a, b, c, above)[0] == -1
    assert orient3d(a, b, c, on)[0] == 0


def test_orient3d_exact_on_nearly_coplanar_points():
    # points on the plane x + y + z = 1 perturbed by one ulp: naive floating point gets signs wrong
    rng = np.random.default_rng(0)
    k = 2000
    P = rng.uniform(-1, 1, size=(4, k, 3)) * 1e3
    P[..., 2] = 1.0 - P[..., 0] - P[..., 1]
    P[3, :, 2] = np.nextafter(P[3, :, 2], rng.choice([-np.inf, np.inf], size=k))
    signs = orient3d(P[0], P[1], P[2], P[3])
    exact = np.array([_exact_sign(P[0, i], P[1, i], P[2, i], P[3, i]) for i in range(k)])
    assert np.array_equal(signs, exact)
    assert np.count_nonzero(exact) > 0


def test_orient3d_exact_scalar_matches_vectorized():
    rng = np.random.default_rng(1)
    P = rng.normal(size=(4, 50, 3))
    vec = orient3d(*P)
    assert all(orient3d_exact(*(p[i] for p in P)) == vec[i] for i in range(50))


def test_orient3d_plane_equals_orient3d_on_nearly_degenerate_points():
    rng = np.random.default_rng(2)
    k = 3000
    P = rng.uniform(-1, 1, size=(4, k, 3)) * 1e3
    P[..., 2] = 1.0 - P[..., 0] - P[..., 1]
    P[3, :, 2] = np.nextafter(P[3, :, 2], rng.choice([-np.inf, np.inf], size=k))
    P[3, :300] = 0.5 * (P[0, :300] + P[1, :300])  # on an edge, up to the midpoint's rounding
    P[3, 300:400] = P[2, 300:400]  # a vertex of the plane
    P[:, 400:600] = rng.normal(size=(4, 200, 3))  # general position
    P[2, 600:700] = P[1, 600:700]  # degenerate plane
    signs = orient3d_plane(*P, *plane_coefficients(P[0], P[1], P[2]))
    assert signs.dtype == np.int8
    assert np.array_equal(signs, orient3d(*P))
    assert np.array_equal(signs[:700:7], [_exact_sign(*(p[i] for p in P)) for i in range(0, 700, 7)])
    assert np.count_nonzero(signs == 0) >= 200 and np.count_nonzero(signs) > 0


def _orient2d(a, b, c):
    return orient2d_int(*exact_integers(a, b, c))


def test_orient2d_exact_collinear_and_turns():
    assert _orient2d((0.0, 0.0), (1.0, 1.0), (2.0, 2.0)) == 0
    assert _orient2d((0.0, 0.0), (1.0, 0.0), (0.0, 1.0)) == 1
    assert _orient2d((0.0, 0.0), (0.0, 1.0), (1.0, 0.0)) == -1
    x = 0.1 + 0.2  # != 0.3 in binary, yet (x, x) lies exactly on the line y = x
    assert _orient2d((0.0, 0.0), (0.3, 0.3), (x, x)) == 0
    det = Fraction(0.3) - 3 * Fraction(0.1)  # 0.1 * 3 != 0.3 in binary: decided exactly
    assert _orient2d((0.0, 0.0), (1.0, 3.0), (0.1, 0.3)) == (det > 0) - (det < 0)


def test_exact_integers_scale_by_one_power_of_two():
    a, b = exact_integers((0.5, 3.0, 0.25), (1e-3, -7.0, 2.0 ** 40))
    scale = Fraction(a[0], 1) / Fraction(0.5)
    assert scale.denominator == 1 and (scale.numerator & (scale.numerator - 1)) == 0
    assert all(Fraction(x) * scale == v for x, v in zip((1e-3, -7.0, 2.0 ** 40), b))
