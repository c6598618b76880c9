"""Factorizations of the RBF interpolation system ``A = [[Phi, Pi], [Pi^T, 0]]`` that grow with the centres.

Two interchangeable solvers for the same interpolant (``fit.update`` in the config):

* :class:`NullSpaceCholesky` (``blocked``, default): the constraint ``Pi^T W = 0`` is eliminated
  with a null-space basis built from 15 unisolvent "P-centres" ``P`` (the first 15):
  ``W = Z a`` with ``Z = [-G; I]``, ``G = Pi_P^{-T} Pi_R^T`` for the remaining centres ``R``. The
  reduced matrix ``B = Z^T Phi Z`` is symmetric positive definite because ``r^2 ln r`` is
  conditionally positive definite of order 2 (here with a quadratic, hence also linear, tail).
  Appending ``m`` centres appends ``m`` rows and columns to ``B``; the Cholesky factor ``L`` of ``B``
  grows by one block row ``[S^T, L~]`` with ``S = L^{-1} B_RJ`` (triangular solves, ``O(r^2 m)``) and
  ``L~ L~^T = B_JJ - S^T S`` (the only factorization, ``O(m^3)``). Old rows never change, so the
  factor is stored and checkpointed as a list of block rows.
* :class:`FullLU` (``full``): the whole ``(n + 15)^2`` system is LU-factorized again after every
  growth step (the "full solve" baseline of S0 Table 1).

Both estimate the 1-norm condition number ``kappa_1(A)`` of the full saddle-point system every
step without ``O(n^3)`` work: :class:`FullLU` with LAPACK ``dgecon`` on its LU factors,
:class:`NullSpaceCholesky` with the same Hager/Higham estimator (LAPACK ``dlacon``) driven by
``O(n^2)`` solves through the factors.
"""

import numpy as np
from scipy.linalg import cho_factor, lu_factor, lu_solve
from scipy.linalg.blas import dtrsm
from scipy.linalg.lapack import dgecon, dpstrf

from posefix.spacetime.rbf import POLY_TERMS
from posefix.mesh.tolerances import ROUNDOFF


class FactorizationError(Exception):
    """The centres do not make a well-posed system (e.g. no 15 unisolvent centres)."""


MAX_CONDITION = 1e13
"""Largest condition number ``kappa_1(A)`` of a fit's system: beyond it the fit is refused
(:func:`posefix.spacetime.fit.iterate`). The largest measured on real libraries is 1.1e11 (cat, reports/bench/
fit-cat-poses.md; 4.5e9 with the defaults); constraint points near one quadric of space-time, which the quadratic
tail cannot tell apart (a float32 sphere scaled uniformly by 1.1), gave 4.2e14-9.0e14 from the first solve, and path
lines with NaN after it. An exact quadric is refused earlier, by :func:`posefix.spacetime.fit.start_fit`."""


def hager_inverse_norm(solve, size, iterations=5):
    """Estimate ``||A^{-1}||_1`` of a symmetric matrix from solves (Hager 1984, Higham 1988).

    Parameters
    ----------
    solve : callable
        ``x -> A^{-1} x`` for (size,) vectors.
    size : int

    Returns
    -------
    float
        A lower bound, usually within a factor 3 of the truth (as LAPACK ``dlacon``).
    """
    x = np.full(size, 1.0 / size)
    y = solve(x)
    est = np.abs(y).sum()
    for it in range(iterations):
        xi = np.where(y >= 0, 1.0, -1.0)
        z = solve(xi)  # A^{-T} = A^{-1}
        j = int(np.argmax(np.abs(z)))
        if it > 0 and np.abs(z[j]) <= z @ x:
            break
        x = np.zeros(size)
        x[j] = 1.0
        y = solve(x)
        new = np.abs(y).sum()
        if new <= est:
            break
        est = new
    alt = np.where(np.arange(size) % 2 == 0, 1.0, -1.0) * (1.0 + np.arange(size) / max(size - 1, 1))
    return max(est, 2.0 * np.abs(solve(alt)).sum() / (3.0 * size))


class NullSpaceCholesky:
    """Blocked Cholesky factorization of the null-space-projected RBF system.

    Centres are numbered in the order they were added; the first 15 are the P-centres.

    Parameters
    ----------
    phi_pp : (15, 15) float
        Kernel matrix of the P-centres.
    pi_p : (15, 15) float
        Polynomial basis at the P-centres (must be invertible).
    """

    def __init__(self, phi_pp, pi_p):
        self.pi_p = np.array(pi_p, dtype=np.float64)
        self.pi_p_lu = lu_factor(self.pi_p)
        self.phi_pp = np.array(phi_pp, dtype=np.float64)
        self.G = np.zeros((POLY_TERMS, 0))            # Pi_P^{-T} Pi_R^T
        self.H = self.phi_pp.copy()                     # Phi[:, P], one row per centre
        self.Pi = self.pi_p.copy()                      # polynomial basis, one row per centre
        self.colsum = np.abs(self.phi_pp).sum(axis=0)   # column sums of |Phi|
        self.S_blocks, self.L_blocks = [], []           # factor block rows [S^T, L~]

    @property
    def n(self):
        """Number of centres."""
        return len(self.Pi)

    def extend(self, phi_jc, phi_jj, pi_j, tol=ROUNDOFF):
        """Append centres ``J``.

        Parameters
        ----------
        phi_jc : (m, n) float
            Kernel between the new centres and the current ones (in centre order).
        phi_jj : (m, m) float
            Kernel among the new centres.
        pi_j : (m, 15) float
            Polynomial basis at the new centres.
        tol : float
            New centres whose Schur-complement pivot keeps less than ``tol`` of their own
            diagonal entry of ``B`` (numerically in the span of the other centres: near-duplicates)
            are dropped.

        Returns
        -------
        (m,) bool
            Which of the new centres were kept (in that order they are appended).
        """
        G_J = lu_solve(self.pi_p_lu, pi_j.T, trans=1)                   # Pi_P^{-T} Pi_J^T
        phi_pj = phi_jc[:, :POLY_TERMS].T                                 # Phi[P, J]
        E = phi_pj - self.phi_pp @ G_J
        B_RJ = phi_jc[:, POLY_TERMS:].T - self.H[POLY_TERMS:] @ G_J - self.G.T @ E
        B_JJ = phi_jj - phi_pj.T @ G_J - G_J.T @ E
        S = self._forward(B_RJ)
        D = B_JJ - S.T @ S
        keep, Lt = _schur_cholesky(0.5 * (D + D.T), np.diag(B_JJ), tol)
        if not keep.any():
            return keep
        S, G_J = S[:, keep], G_J[:, keep]
        self.S_blocks.append(np.ascontiguousarray(S.T))
        self.L_blocks.append(np.asfortranarray(Lt))
        self.G = np.concatenate([self.G, G_J], axis=1)
        self.colsum = np.concatenate([self.colsum + np.abs(phi_jc[keep]).sum(axis=0),
                                      np.abs(phi_jc[keep]).sum(axis=1) + np.abs(phi_jj[np.ix_(keep, keep)]).sum(axis=0)])
        self.H = np.concatenate([self.H, phi_jc[keep, :POLY_TERMS]])
        self.Pi = np.concatenate([self.Pi, pi_j[keep]])
        return keep

    def solve(self, V):
        """Weights and polynomial coefficients interpolating ``V`` (n, k) at the centres.

        Returns
        -------
        W : (n, k) float
        U : (15, k) float
        """
        return self._solve(V, np.zeros((POLY_TERMS, V.shape[1])))

    def _solve(self, V, q):
        """Solve ``A [W; U] = [V; q]`` through the factors (``O(n^2)`` per column)."""
        P = POLY_TERMS
        w_p = lu_solve(self.pi_p_lu, q, trans=1)                # particular solution, P part
        rhs_full = V - self.H @ w_p                             # V - Phi w_p
        rhs = rhs_full[P:] - self.G.T @ rhs_full[:P]
        a = self._backward(self._forward(rhs))
        W = np.empty_like(V)
        W[P:] = a
        W[:P] = w_p - self.G @ a
        U = lu_solve(self.pi_p_lu, V[:P] - self.H.T @ W)
        return W, U

    def condition(self):
        """Estimate of ``kappa_1(A)`` of the full (n + 15) saddle-point system."""
        n, P = self.n, POLY_TERMS

        def solve(x):
            W, U = self._solve(x[:n, None], x[n:, None])
            return np.concatenate([W[:, 0], U[:, 0]])

        abs_pi = np.abs(self.Pi)
        norm = max((self.colsum + abs_pi.sum(axis=1)).max(), abs_pi.sum(axis=0).max())
        return norm * hager_inverse_norm(solve, n + P)

    def _forward(self, B):
        """Solve ``L X = B`` block row by block row."""
        X = np.empty_like(B)
        start = 0
        for S, Lt in zip(self.S_blocks, self.L_blocks):
            end = start + len(Lt)
            X[start:end] = dtrsm(1.0, Lt, B[start:end] - S @ X[:start], lower=1)
            start = end
        return X

    def _backward(self, Y):
        """Solve ``L^T X = Y`` block row by block row, last first."""
        X = Y.copy()
        end = len(Y)
        for S, Lt in zip(reversed(self.S_blocks), reversed(self.L_blocks)):
            start = end - len(Lt)
            X[start:end] = dtrsm(1.0, Lt, X[start:end], lower=1, trans_a=1)
            X[:start] -= S.T @ X[start:end]
            end = start
        return X

    def state(self):
        """Arrays that restore the factorization exactly (:meth:`from_state`)."""
        out = {"pi_p": self.pi_p, "phi_pp": self.phi_pp, "G": self.G, "H": self.H, "Pi": self.Pi}
        for k, (S, Lt) in enumerate(zip(self.S_blocks, self.L_blocks)):
            out[f"S/{k:05d}"], out[f"L/{k:05d}"] = S, Lt
        return out

    @classmethod
    def from_state(cls, state):
        """Rebuild exactly from :meth:`state` arrays; ``colsum`` (only used by :meth:`condition`)
        must be set by the caller."""
        self = cls(state["phi_pp"], state["pi_p"])
        blocks = sum(1 for key in state if key.startswith("L/"))
        self.S_blocks = [state[f"S/{k:05d}"] for k in range(blocks)]
        self.L_blocks = [state[f"L/{k:05d}"] for k in range(blocks)]
        self.G, self.H, self.Pi = state["G"], state["H"], state["Pi"]
        return self


class FullLU:
    """The full ``(n + 15)^2`` system, LU-factorized from scratch after every growth step."""

    def __init__(self, phi_pp, pi_p):
        self.Phi = np.array(phi_pp, dtype=np.float64)
        self.Pi = np.array(pi_p, dtype=np.float64)
        self._factor()

    @property
    def n(self):
        return len(self.Pi)

    def extend(self, phi_jc, phi_jj, pi_j, tol=None):
        """Append centres (see :meth:`NullSpaceCholesky.extend`); all are kept."""
        self.Phi = np.block([[self.Phi, phi_jc.T], [phi_jc, phi_jj]])
        self.Pi = np.concatenate([self.Pi, pi_j])
        self._factor()
        return np.ones(len(pi_j), dtype=bool)

    def _factor(self):
        n, P = self.n, POLY_TERMS
        A = np.zeros((n + P, n + P))
        A[:n, :n], A[:n, n:], A[n:, :n] = self.Phi, self.Pi, self.Pi.T
        self.norm = np.abs(A).sum(axis=0).max()
        self.lu = lu_factor(A, check_finite=False)

    def solve(self, V):
        """Weights (n, k) and polynomial coefficients (15, k) interpolating ``V``."""
        X = lu_solve(self.lu, np.concatenate([V, np.zeros((POLY_TERMS, V.shape[1]))]), check_finite=False)
        return X[:self.n], X[self.n:]

    def condition(self):
        """``kappa_1(A)`` from LAPACK ``dgecon`` on the LU factors."""
        rcond, info = dgecon(self.lu[0], self.norm, norm="1")
        return np.inf if rcond == 0 else 1.0 / rcond


def _schur_cholesky(D, own, tol):
    """Cholesky factor of the Schur complement ``D``, dropping new centres it cannot carry.

    A centre is kept when its pivot is at least ``tol`` times ``own`` (its diagonal entry before
    the existing centres were projected out). Returns the kept mask (m,) and the lower factor of
    ``D[keep][:, keep]``.
    """
    m = len(D)
    own = np.maximum(own, np.finfo(float).tiny)
    try:
        L, _ = cho_factor(D, lower=True, check_finite=False)
        if np.all(np.diag(L) ** 2 >= tol * own):
            return np.ones(m, dtype=bool), np.tril(L)
    except np.linalg.LinAlgError:
        pass
    s = 1.0 / np.sqrt(own)
    c, piv, rank, _ = dpstrf(D * s[:, None] * s[None, :], tol=tol, lower=1)
    rank = int(np.sum(np.diag(c)[:rank] ** 2 >= tol))  # LAPACK always accepts its first pivot
    keep = np.zeros(m, dtype=bool)
    keep[piv[:rank] - 1] = True
    if not keep.any():
        return keep, np.zeros((0, 0))
    L, _ = cho_factor(D[np.ix_(keep, keep)], lower=True, check_finite=False)
    return keep, np.tril(L)
