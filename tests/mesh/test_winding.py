"""Generalized winding numbers: analytic values on spheres, open and flipped surfaces."""

import numpy as np

from conftest import icosphere
from posefix.mesh.winding import fast_winding_numbers, winding_numbers


def _solid_angle_direct(V, F, P):
    """Reference: Van Oosterom-Strackee per pair without the dot-product expansion."""
    a, b, c = (V[F[:, i]][None] - P[:, None] for i in range(3))
    la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
    det = np.einsum("pfi,pfi->pf", a, np.cross(b, c))
    den = (la * lb * lc + np.einsum("pfi,pfi->pf", a, b) * lc + np.einsum("pfi,pfi->pf", b, c) * la
           + np.einsum("pfi,pfi->pf", c, a) * lb)
    return np.arctan2(det, den).sum(axis=1) / (2 * np.pi)


def test_inside_a_closed_sphere_is_one_outside_zero():
    V, F = icosphere(3, centre=(5.0, -2.0, 1.0))
    P = np.array([[5.0, -2.0, 1.0], [5.5, -1.8, 1.3], [5.0, -2.0, 2.5], [20.0, 0.0, 0.0], [5.0, -2.0, 1.01]])
    w = winding_numbers(V, F, P)
    assert np.allclose(w, [1, 1, 0, 0, 1], atol=1e-9)


def test_orientation_flip_gives_minus_one():
    V, F = icosphere(2)
    assert np.allclose(winding_numbers(V, F[:, ::-1], np.zeros((1, 3))), -1.0, atol=1e-9)


def test_half_a_sphere_seen_from_its_centre_is_one_half():
    V, F = icosphere(4)
    upper = F[V[F].mean(axis=1)[:, 2] > 0]
    w = winding_numbers(V, upper, np.zeros((1, 3)))
    assert abs(w[0] - 0.5) < 0.02  # the polygonal cut is not exactly the equator


def test_matches_the_direct_formula_on_many_blocks_and_an_overlapping_mesh():
    V1, F1 = icosphere(2)
    V2, F2 = icosphere(2, centre=(0.5, 0.0, 0.0))
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])  # self-intersecting: w = 2 in the overlap
    P = np.random.default_rng(0).uniform(-1.5, 2.0, size=(400, 3))
    w = winding_numbers(V, F, P)
    assert np.allclose(w, _solid_angle_direct(V, F, P), atol=1e-9)
    assert np.allclose(winding_numbers(V, F, [[0.25, 0.0, 0.0]]), 2.0, atol=1e-9)
    assert np.array_equal(w, winding_numbers(V, F, P))  # deterministic


def test_empty_inputs():
    V, F = icosphere(1)
    assert winding_numbers(V, F, np.zeros((0, 3))).shape == (0,)
    assert np.all(winding_numbers(V, F[:0], np.zeros((2, 3))) == 0)


def test_the_far_field_approximation_is_close_to_exact():
    V1, F1 = icosphere(3)
    V2, F2 = icosphere(3, centre=(0.5, 0.0, 0.0))
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    P = np.random.default_rng(0).uniform(-2.0, 2.5, size=(500, 3))
    exact = winding_numbers(V, F, P)
    fast = fast_winding_numbers(V, F, P, beta=2.0, leaf_size=16)  # 160 clusters: most pairs far field
    assert np.abs(fast - exact).max() < 0.02
    assert np.allclose(fast_winding_numbers(V, F, P, beta=1e9), exact, atol=1e-9)  # all near: exact
    assert np.array_equal(fast, fast_winding_numbers(V, F, P, beta=2.0, leaf_size=16))
