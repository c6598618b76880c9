"""Gauss–Newton with step halving for sums of squared residuals with a sparse Jacobian.

The energy is a :class:`posefix.mesh.shells.ShellEnergy` (residuals and Jacobian of discrete shells).
"""

import logging
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from posefix.mesh.geometry import face_areas
from posefix.mesh.sparse import CholeskySequence, fill_reducing_order
from posefix.mesh.tolerances import TINY

log = logging.getLogger(__name__)

STOP_REASONS = ("converged", "stall", "max_iters", "line-search failure", "collapsed triangle")
"""Why a run stopped, in the order of downstream.h5's ``reason`` codes."""


@dataclass
class SolveResult:
    """Outcome of :func:`gauss_newton`.

    ``V`` (n, 3) float final positions; ``errors`` (iterations + 1,) energy after every accepted
    step (``errors[0]`` at the start); ``steps`` (iterations,) accepted step lengths; ``reason`` one
    of ``STOP_REASONS``; ``gradient_reduction`` |J^T r| at the start over at the end;
    ``min_area_ratio`` smallest face area over its rest area at the end.
    """
    V: np.ndarray
    errors: np.ndarray
    steps: np.ndarray
    converged: bool
    reason: str
    gradient_reduction: float
    min_area_ratio: float
    seconds: float = 0.0

    @property
    def iterations(self):
        return len(self.steps)


@dataclass
class SolverSettings:
    """Stopping rules of :func:`gauss_newton`; dimensionless.

    It stops when the energy is zero, when the relative decrease falls below ``rel_tol``, when no step lowers
    it, after ``stall_iters`` creeping steps in a row, or after ``max_iters``. "Converged" means it: the energy
    is zero (``energy_tol``), or the last step was a full one and |J^T r| dropped by ``gradient_drop`` from the
    start. Anything else is not converged, with the reason (:data:`STOP_REASONS`): "collapsed triangle" when a
    face ended below ``collapse`` of its rest area, otherwise "line-search failure", "max_iters" or "stall".
    """
    max_iters: int = 200        # Gauss-Newton iterations at most
    rel_tol: float = 1e-6       # stop when (E_prev - E) / E_prev falls below this
    energy_tol: float = 1e-16   # E at or below this is zero: converged
    gradient_drop: float = 1e4  # converged: a full step accepted and |J^T r| reduced this much
    min_step: float = 1e-10     # line search: halve from 1 down to this, then give up
    stall_step: float = 1e-3    # an accepted step below this is a creeping step ...
    stall_iters: int = 10       # ... and this many in a row stop the run as stalled
    collapse: float = 1e-5      # a face below this fraction of its rest area has collapsed


def gauss_newton(energy, V0, handles, handle_positions, F, settings=None):
    """Minimize a :class:`ShellEnergy` by Gauss–Newton with step halving, handles fixed.

    Each iteration solves J^T J d = -J^T r over the free coordinates (:func:`unknowns`, sparse Cholesky) and takes
    the first of the steps 1, 1/2, ... that lowers the energy; when it stops and why: :class:`SolverSettings`.

    Parameters
    ----------
    energy : ShellEnergy
    V0 : (n, 3) float
        Start positions (the handles are moved to ``handle_positions`` first).
    handles : (k,) int
        Fixed vertices (k >= 3 not collinear removes the rigid motions).
    handle_positions : (k, 3) float
    F : (m, 3) int
        Faces (for the collapse check).
    settings : SolverSettings, optional

    Returns
    -------
    SolveResult
    """
    s, start = settings or SolverSettings(), time.perf_counter()
    V = np.array(V0, dtype=float)
    V[handles] = handle_positions
    free, factors = unknowns(energy.jacobian(V), handles), CholeskySequence()  # J's pattern stays: one analysis
    r = energy.residuals(V)
    errors, steps, creeping, g0 = [float(r @ r)], [], 0, None  # one log line per iteration at debug level
    while True:
        J = energy.jacobian(V)[:, free]
        g = J.T @ r
        g0 = g if g0 is None else g0
        reason = _stop_reason(J, errors[-1], len(steps), s)
        accepted = None if reason else _line_search(energy, V, free, _step(J, g, factors), errors[-1], s.min_step)
        if accepted is None:
            reason = reason or "line-search failure"
            break
        V, r, step = accepted
        errors.append(float(r @ r))
        steps.append(step)
        log.debug("GN %3d: E %.6e step %.3g", len(steps), errors[-1], step)
        creeping = creeping + 1 if step < s.stall_step else 0
        if creeping >= s.stall_iters:
            reason = "stall"
            break
        if (errors[-2] - errors[-1]) / errors[-2] < s.rel_tol and errors[-1] > s.energy_tol:
            g, reason = energy.jacobian(V)[:, free].T @ r, "stall"
            break
    reduction = float(np.linalg.norm(g0) / max(np.linalg.norm(g), TINY))
    return _result(V, (errors, steps), reason, reduction, face_areas(np.asarray(V0, dtype=float), F), F, s, start)


def _stop_reason(J, energy, iterations, s):
    """Why to stop before the next step (a reason of :data:`STOP_REASONS`), or None: the energy is zero, the
    iterations ran out, or the Jacobian ``J`` is not finite (a face collapsed to zero area)."""
    if energy <= s.energy_tol:
        return "converged"
    if iterations == s.max_iters:
        return "max_iters"
    if not np.all(np.isfinite(J.data)):
        return "collapsed triangle"
    return None


def _line_search(energy, V, free, delta, e0, min_step):
    """``(X (n, 3), residuals, step)``: the first of the steps 1, 1/2, ... down to ``min_step`` along ``delta`` (over
    the ``free`` coordinates) whose energy is below ``e0``; None when none is (or ``delta`` is None)."""
    step = 1.0
    while delta is not None and step >= min_step:
        X = V.copy()
        X.reshape(-1)[free] += step * delta
        rx = energy.residuals(X)
        if float(rx @ rx) < e0:
            return X, rx, step
        step *= 0.5
    return None


def _result(V, history, reason, reduction, rest_area, F, s, start):
    """The :class:`SolveResult` of a run that stopped at ``V`` for ``reason``; ``history``: (energies, steps).

    "Converged" also when the last step was a full one and |J^T r| dropped by ``gradient_drop`` (``reduction``);
    a run that is not converged and has a face below ``collapse`` of its rest area (``rest_area`` (m,)) stopped
    because of it: "collapsed triangle" (the bending gradient grows like 1 / area)."""
    errors, steps = history
    if reason != "converged" and steps and steps[-1] == 1.0 and reduction >= s.gradient_drop:
        reason = "converged"
    ratio = float(np.min(face_areas(V, F) / np.maximum(rest_area, TINY)))
    if reason != "converged" and ratio < s.collapse:
        reason = "collapsed triangle"
    return SolveResult(V, np.array(errors), np.array(steps), reason == "converged", reason, reduction, ratio,
                       time.perf_counter() - start)


def unknowns(J, handles):
    """The free coordinates in a fill-reducing elimination order of J^T J, vertex by vertex.

    Parameters
    ----------
    J : (r, 3 n) scipy.sparse matrix
        A Jacobian (its pattern: column ``3 v + c`` for coordinate c of vertex v).
    handles : (k,) int
        Fixed vertices.

    Returns
    -------
    (3 (n - k),) int64
        Columns of ``J``: the three coordinates of every free vertex, the vertices in the order of
        :func:`~posefix.mesh.sparse.fill_reducing_order` of their pattern in J^T J.
    """
    n = J.shape[1] // 3
    free = np.setdiff1d(np.arange(n), handles)
    coo = sp.coo_matrix(J)
    touches = sp.csr_matrix((np.ones(coo.nnz), (coo.row, coo.col // 3)), shape=(J.shape[0], n))[:, free]
    order = free[fill_reducing_order(touches.T @ touches)]
    return (3 * order[:, None] + np.arange(3)).reshape(-1)


def _step(J, g, factors):
    """The Gauss–Newton step d solving J^T J d = -g, (k,) float; None when J^T J is singular.

    ``J`` (r, k) sparse has its columns in elimination order (:func:`unknowns`), ``g`` = J^T r (k,);
    ``factors``: the run's :class:`~posefix.mesh.sparse.CholeskySequence` (one analysis of J^T J's pattern).
    """
    H = (J.T @ J).tocsr()  # sorted indices; symmetric, so its CSR arrays are its CSC arrays
    try:
        factor = factors.factorized(sp.csc_matrix((H.data, H.indices, H.indptr), shape=H.shape), np.arange(H.shape[0]))
    except np.linalg.LinAlgError:  # not positive definite
        return None
    d = factor.solve(-g)
    return d if np.all(np.isfinite(d)) else None
