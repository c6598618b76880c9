"""RBF model and its factorizations: interpolation, polynomial reproduction, blocked == full, kappa."""

import numpy as np
from scipy.interpolate import RBFInterpolator

from test_factorization import _grow, _system
from posefix.spacetime.factorization import FullLU, NullSpaceCholesky
from posefix.spacetime.rbf import POLY_TERMS, RBFField, kernel, kernel_matrix, normalization, poly_basis


def test_kernel_values():
    r = np.array([0.0, 0.5, 1.0, 2.0])
    assert np.allclose(kernel(r ** 2), [0.0, 0.25 * np.log(0.5), 0.0, 4 * np.log(2.0)], atol=1e-16)


def test_exact_interpolation_at_the_centres():
    Z, K, Pi, V = _system(500, seed=1)
    solver = _grow(NullSpaceCholesky, K, Pi, [128, 128, 229])
    W, U = solver.solve(V)
    field = RBFField(Z, W, U, np.zeros(4), 1.0)
    assert np.abs(field(Z) - V).max() <= 1e-9 * np.abs(V).max()
    assert np.abs(Pi.T @ W).max() <= 1e-9 * np.abs(W).max()  # orthogonality condition


def test_quadratic_polynomials_are_reproduced_exactly():
    Z, K, Pi, _ = _system(300, seed=2)
    rng = np.random.default_rng(3)
    coef = rng.normal(size=(POLY_TERMS, 3))
    solver = _grow(NullSpaceCholesky, K, Pi, [285])
    W, U = solver.solve(Pi @ coef)
    assert np.abs(W).max() <= 1e-8 * np.abs(coef).max()
    assert np.allclose(U, coef, atol=1e-8)
    probe = rng.uniform(-1, 1, size=(50, 4))
    assert np.allclose(RBFField(Z, W, U, np.zeros(4), 1.0)(probe), poly_basis(probe) @ coef, atol=1e-8)


def test_interpolant_does_not_depend_on_the_normalization():
    rng = np.random.default_rng(4)
    Y = rng.uniform(0, 7, size=(200, 4)) + [10, -3, 2, 0]
    V = rng.normal(size=(200, 3))
    fields = []
    for shift, scale in (normalization(Y), (np.zeros(4), 1.0)):
        Z = (Y - shift) / scale
        solver = _grow(FullLU, kernel_matrix(Z, Z), poly_basis(Z), [185])
        W, U = solver.solve(V)
        fields.append(RBFField(Y, W, U, shift, scale))
    probe = rng.uniform(0, 7, size=(100, 4)) + [10, -3, 2, 0]
    assert np.allclose(fields[0](probe), fields[1](probe), atol=1e-6 * np.abs(fields[1](probe)).max())


def test_same_interpolant_as_scipy_thin_plate_spline():
    # scipy's thin_plate_spline is r^2 log r; degree=2 adds the same quadratic polynomial space
    Z, K, Pi, V = _system(400, seed=5)
    W, U = _grow(NullSpaceCholesky, K, Pi, [385]).solve(V)
    ours = RBFField(Z, W, U, np.zeros(4), 1.0)
    peer = RBFInterpolator(Z, V, kernel="thin_plate_spline", degree=2)
    probe = np.random.default_rng(6).uniform(-0.5, 0.5, size=(200, 4))
    assert np.abs(ours(probe) - peer(probe)).max() <= 1e-8 * np.abs(peer(probe)).max()
