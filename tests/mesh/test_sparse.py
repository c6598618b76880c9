"""The sparse direct solver: exact on a Laplacian system, the same in symmetric mode, singular matrices refused;
a fill-reducing order computed once gives the ordering's fill; the Cholesky back end (CHOLMOD, or SuperLU's symmetric
mode without it) solves the same system, one or many right-hand sides; a sequence of matrices of one pattern is
analysed once."""

import builtins

import numpy as np
import pytest
import scipy.sparse as sp

from conftest import icosphere
from posefix.mesh.laplacian import cotangent_laplacian
from posefix.mesh import sparse
from posefix.mesh.sparse import cholesky_factorized, factorized, fill_reducing_order


def _pinned_laplacian():
    V, F = icosphere(2)
    L = cotangent_laplacian(V, F)
    free = np.arange(1, len(V))  # pin vertex 0: non-singular, symmetric positive definite
    return L[free][:, free], np.random.default_rng(0).normal(size=(len(free), 3))


@pytest.mark.parametrize("ordering, symmetric", [("COLAMD", False), ("MMD_AT_PLUS_A", False), ("MMD_AT_PLUS_A", True)])
def test_solves_a_pinned_cotangent_laplacian(ordering, symmetric):
    A, b = _pinned_laplacian()
    x = factorized(A, ordering=ordering, symmetric=symmetric).solve(b)
    assert np.abs(A @ x - b).max() < 1e-10 * np.abs(b).max()


def test_a_diagonal_system_and_a_singular_one():
    assert factorized(sp.diags([2.0, 4.0])).solve(np.array([1.0, 1.0])).tolist() == [0.5, 0.25]
    with pytest.raises(RuntimeError):
        factorized(sp.csc_matrix(np.array([[1.0, 1.0], [1.0, 1.0]])))


def test_a_fill_reducing_order_computed_once_keeps_the_orderings_fill():
    A, b = _pinned_laplacian()
    p = fill_reducing_order(A)
    assert np.array_equal(np.sort(p), np.arange(A.shape[0]))
    fill = lambda lu: lu.L.nnz + lu.U.nnz
    ordered = factorized(A.tocsr()[p][:, p], ordering="NATURAL", symmetric=True)
    assert fill(ordered) == fill(factorized(A, ordering="MMD_AT_PLUS_A", symmetric=True))
    assert fill(ordered) < fill(factorized(A, ordering="NATURAL", symmetric=True))
    x = np.empty_like(b)
    x[p] = ordered.solve(b[p])
    assert np.abs(A @ x - b).max() < 1e-10 * np.abs(b).max()


def _without_cholmod(monkeypatch):
    real_import = builtins.__import__

    def refuse(name, *args, **kwargs):
        if name.startswith("sksparse"):
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", refuse)
    sparse._cholmod_analyze.cache_clear()


@pytest.fixture(params=["cholmod", "superlu"])
def back_end(request, monkeypatch):
    """The Cholesky back end of a test: CHOLMOD (skipped when it is not installed) or SuperLU (CHOLMOD's import
    refused)."""
    if request.param == "cholmod":
        pytest.importorskip("sksparse.cholmod", reason="scikit-sparse (CHOLMOD) is not installed: `make` builds it")
    else:
        _without_cholmod(monkeypatch)
        request.addfinalizer(sparse._cholmod_analyze.cache_clear)
    return request.param


def test_the_cholesky_back_ends_solve_a_pinned_cotangent_laplacian(back_end, caplog):
    A, b = _pinned_laplacian()
    solver = cholesky_factorized(A)
    x = solver.solve(b)
    assert np.abs(A @ x - b).max() < 1e-10 * np.abs(b).max()
    assert np.abs(A @ solver.solve(b[:, 0]) - b[:, 0]).max() < 1e-10 * np.abs(b).max()
    ordered = cholesky_factorized(A, fill_reducing_order(A)).solve(b)
    assert np.abs(ordered - x).max() < 1e-10 * np.abs(x).max()
    assert ("CHOLMOD) is not installed" in caplog.text) == (back_end == "superlu")


def test_the_cholesky_back_ends_refuse_a_singular_matrix_alike(back_end):
    with pytest.raises(np.linalg.LinAlgError):  # singular: a zero pivot
        cholesky_factorized(sp.csc_matrix(np.diag([1.0, 0.0])))


def test_a_cholesky_sequence_analyses_a_pattern_once_and_again_when_an_entry_leaves_it(back_end):
    A, b = _pinned_laplacian()
    A = sp.csc_matrix(A)
    sequence = sparse.CholeskySequence()
    for scale in (1.0, 2.0, 5.0):  # one pattern, other values: one analysis
        x = sequence.factorized(scale * A).solve(b)
        assert np.abs(scale * A @ x - b).max() < 1e-10 * np.abs(b).max()
    corner = sp.csc_matrix(([0.1, 0.1], ([0, A.shape[0] - 1], [A.shape[0] - 1, 0])), shape=A.shape)
    B = A + corner  # an entry outside the pattern (a new contact pair): analysed again, with the old pattern
    x = sequence.factorized(B).solve(b)
    assert np.abs(B @ x - b).max() < 1e-10 * np.abs(b).max()
    x = sequence.factorized(A).solve(b)  # within the union: no new analysis
    assert np.abs(A @ x - b).max() < 1e-10 * np.abs(b).max()
    assert sequence.analyses == (2 if back_end == "cholmod" else 0)
    with pytest.raises(np.linalg.LinAlgError):  # singular: a zero pivot
        sequence.factorized(sp.csc_matrix(np.diag([1.0, 0.0])))
