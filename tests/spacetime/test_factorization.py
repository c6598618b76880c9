"""Factorizations of the RBF system: blocked Cholesky updates against full solves, condition estimates, state."""

import numpy as np
import pytest

from posefix.spacetime.factorization import FullLU, NullSpaceCholesky, hager_inverse_norm
from posefix.spacetime.rbf import POLY_TERMS, kernel_matrix, poly_basis


def _system(n, seed=0):
    rng = np.random.default_rng(seed)
    Z = rng.uniform(-0.5, 0.5, size=(n, 4))
    return Z, kernel_matrix(Z, Z), poly_basis(Z), rng.normal(size=(n, 3))


def _grow(cls, K, Pi, sizes):
    solver = cls(K[:POLY_TERMS, :POLY_TERMS], Pi[:POLY_TERMS])
    n = POLY_TERMS
    for m in sizes:
        J = np.arange(n, n + m)
        solver.extend(K[J][:, :n], K[np.ix_(J, J)], Pi[J])
        n += m
    return solver


def test_blocked_updates_equal_a_full_solve_over_growth_steps():
    Z, K, Pi, V = _system(700)
    blocked, n = NullSpaceCholesky(K[:15, :15], Pi[:15]), POLY_TERMS
    for step, m in enumerate([40, 128, 1, 128, 200, 188]):
        J = np.arange(n, n + m)
        blocked.extend(K[J][:, :n], K[np.ix_(J, J)], Pi[J])
        n += m
        full = FullLU(K[:n, :n], Pi[:n])
        Wb, Ub = blocked.solve(V[:n])
        Wf, Uf = full.solve(V[:n])
        assert np.abs(Wb - Wf).max() <= 1e-8 * np.abs(Wf).max(), step
        assert np.abs(Ub - Uf).max() <= 1e-8 * np.abs(Uf).max(), step
        # both estimate the same kappa_1 of the saddle-point system
        assert np.isclose(blocked.condition(), full.condition(), rtol=1e-6)


def test_condition_estimate_is_close_to_the_exact_one_norm_condition():
    Z, K, Pi, _ = _system(120, seed=7)
    solver = _grow(NullSpaceCholesky, K, Pi, [105])
    A = np.block([[K, Pi], [Pi.T, np.zeros((15, 15))]])
    exact = np.linalg.cond(A, 1)
    assert exact / 3 <= solver.condition() <= exact * (1 + 1e-9)
    inv = np.linalg.inv(A)
    assert np.isclose(hager_inverse_norm(lambda x: inv @ x, len(A)), np.abs(inv).sum(axis=0).max(), rtol=0.5)


def test_near_duplicate_centres_are_dropped_not_fatal():
    Z, K, Pi, V = _system(100, seed=8)
    Z2 = np.vstack([Z, Z[20:25] + 1e-13])  # five near-copies of existing centres
    K2, Pi2 = kernel_matrix(Z2, Z2), poly_basis(Z2)
    solver = _grow(NullSpaceCholesky, K2, Pi2, [85])
    J = np.arange(100, 105)
    keep = solver.extend(K2[J][:, :100], K2[np.ix_(J, J)], Pi2[J])
    assert keep.sum() == 0 and solver.n == 100


@pytest.mark.parametrize("cls", [NullSpaceCholesky, FullLU])
def test_state_round_trip(cls):
    Z, K, Pi, V = _system(300, seed=9)
    solver = _grow(cls, K, Pi, [100, 185])
    if cls is NullSpaceCholesky:
        restored = NullSpaceCholesky.from_state(solver.state())
        W1, U1 = solver.solve(V)
        W2, U2 = restored.solve(V)
        assert np.array_equal(W1, W2) and np.array_equal(U1, U2)
