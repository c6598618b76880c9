"""Greedy RBF fitting of the space-time vector field (S0 §4.2, "RBF center selection").

1. **Seed.** Farthest-point sampling over all constraints, starting from the two most distant
   points (S0's start), until ``batch`` centres are chosen: 15 polynomial terms need at least 15
   unisolvent centres before the first solve. The 15 best-conditioned of them (pivoted QR of the
   polynomial basis) become the P-centres of :class:`posefix.spacetime.factorization.NullSpaceCholesky`.
2. **Iterate.** Solve for the weights, evaluate the residual ``|f(y) - c'|`` at every constraint,
   and stop when its maximum drops below ``eps`` (or the rms below ``eps_rms``, or ``max_centers``
   is reached). Otherwise take the ``candidates`` (p) constraints with the largest residual and add
   ``batch`` (m) of them: by farthest-point sampling *within that candidate set*, starting from the
   worst (``selection="fps"``, S0), or simply the m worst (``selection="worst"``, Carr et al. 2001).
3. **Update.** Grow the factorization by the new centres (blocked, or full refactorization).

The kernel values between all constraints and the centres are kept in one preallocated
(constraints x max_centres) array that grows by ``batch`` columns per iteration, which makes the
residual a matrix product. Above ``memory_bytes`` the residual is recomputed at every iteration:
on an OpenCL device when one is given (:class:`posefix.spacetime.integration_opencl.FieldEvaluator`,
5x faster than numpy on one CPU thread at 150k constraints x 4k centres: reports/bench/scale.md), else
in numpy chunks.

Everything is deterministic; a fit can be resumed from :meth:`GreedyFit.state` and continues
exactly as an uninterrupted one.
"""

import logging
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import qr
from scipy.spatial.distance import cdist

from posefix.spacetime.factorization import MAX_CONDITION, FactorizationError, FullLU, NullSpaceCholesky
from posefix.spacetime.rbf import POLY_TERMS, RBFField, kernel, kernel_matrix, normalization, poly_basis
from posefix.mesh.tolerances import ROUNDOFF

log = logging.getLogger(__name__)

SOLVERS = {"blocked": NullSpaceCholesky, "full": FullLU}
STOP_REASONS = ("eps", "rms", "max_centers", "exhausted")
_CHUNK = 4096


@dataclass(frozen=True)
class FitSettings:
    """Parameters of the greedy fit (lengths in the units of the constraint points).

    ``eps`` / ``eps_rms``: stop when the max / rms residual is below (``eps_rms = 0`` disables).
    ``candidates`` (p), ``batch`` (m): S0 used 1024 and 128.
    """

    eps: float
    eps_rms: float = 0.0
    max_centers: int = 4000
    candidates: int = 1024
    batch: int = 128
    selection: str = "fps"
    update: str = "blocked"
    memory_bytes: float = 8e9
    pivot_tol: float = ROUNDOFF

    def selection_key(self):
        """Parameters that determine the sequence of centres (not where it stops)."""
        return {"candidates": self.candidates, "batch": self.batch, "selection": self.selection,
                "update": self.update, "pivot_tol": self.pivot_tol}


@dataclass
class GreedyFit:
    """State of a greedy fit: the centres (as constraint indices, in order), solver, history."""

    settings: FitSettings
    points: np.ndarray
    values: np.ndarray
    shift: np.ndarray
    scale: float
    order: np.ndarray
    solver: object
    history: list = field(default_factory=list)
    stop_reason: str = ""
    weights: np.ndarray = None
    poly: np.ndarray = None
    residual: np.ndarray = None
    evaluator: object = None
    pending: dict = None

    @property
    def n(self):
        return len(self.order)

    def field(self):
        """The fitted :class:`posefix.spacetime.rbf.RBFField`."""
        return RBFField(self.points[self.order], self.weights, self.poly, self.shift, self.scale)

    def state(self):
        """Arrays that let :func:`resume_fit` continue exactly where this fit is (or from an earlier
        iteration: everything is append-only, so prefixes stay valid)."""
        out = {"order": self.order}
        if isinstance(self.solver, NullSpaceCholesky):
            out.update({f"solver/{k}": v for k, v in self.solver.state().items()})
        return out


def cache_fits(count, settings):
    """Whether the kernel between ``count`` constraints and ``settings.max_centers`` centres fits the budget."""
    return count * settings.max_centers * 8 <= settings.memory_bytes


def fit_memory(count, max_centers):
    """Bytes a fit of ``count`` constraints needs besides the kernel cache (estimate).

    Constraint arrays, normalized points, polynomial basis and residual (~32 floats per constraint),
    the factorization and its workspace (~2 floats per entry of the centres' kernel matrix), and
    0.5 GB for the interpreter and libraries.
    """
    return 8.0 * (32 * count + 2 * max_centers ** 2) + 0.5e9


def start_fit(points, values, settings, device=None):
    """Seed a fit: farthest-point seed set, P-centres, first factorization (no solve yet).

    Parameters
    ----------
    points : (N, 4) float
        Constraint points (space-time).
    values : (N, 3) float
        Constraint tangents.
    settings : FitSettings
    device : pyopencl.Device, optional
        Evaluates the residual when the kernel cache exceeds ``settings.memory_bytes`` (else numpy).

    Raises
    ------
    FactorizationError
        Fewer than 15 constraints, or constraints that do not determine a quadratic.
    """
    if len(points) < POLY_TERMS:
        raise FactorizationError(f"{len(points)} constraints; at least {POLY_TERMS} are needed")
    shift, scale = normalization(points)
    Z = (points - shift) / scale
    seed = farthest_points(Z, min(settings.batch, settings.max_centers, len(Z)), _diameter_pair(Z))
    basis = poly_basis(Z[seed])
    _, R, piv = qr(basis.T, pivoting=True, mode="economic")
    if len(seed) < POLY_TERMS or abs(R[POLY_TERMS - 1, POLY_TERMS - 1]) < 1e-10 * abs(R[0, 0]):
        raise FactorizationError("the constraint points do not determine a quadratic polynomial "
                                 "(too few, or all on one quadric)")
    p_idx = seed[np.sort(piv[:POLY_TERMS])]
    rest = seed[~np.isin(seed, p_idx)]
    solver = SOLVERS[settings.update](kernel_matrix(Z[p_idx], Z[p_idx]), poly_basis(Z[p_idx]))
    fit = GreedyFit(settings, points, values, shift, scale, p_idx, solver)
    _Evaluator.attach(fit, device)
    start = time.perf_counter()
    dropped = _extend(fit, rest) if len(rest) else 0
    fit.pending = {"seconds_select": 0.0, "seconds_update": time.perf_counter() - start, "dropped": dropped}
    return fit


def resume_fit(points, values, settings, state, history, device=None):
    """Rebuild the fit at the end of ``history`` from :meth:`GreedyFit.state` (possibly of a longer fit).

    ``device`` as in :func:`start_fit`. The kernel cache is recomputed and the factorization restored bit for bit (blocked) or
    refactorized (full), so that continuing gives exactly what an uninterrupted fit gives.
    """
    shift, scale = normalization(points)
    Z = (points - shift) / scale
    n = history[-1]["centers"]
    order = np.asarray(state["order"][:n], dtype=np.int64)
    if settings.update == "blocked":
        solver_state = {k[len("solver/"):]: v for k, v in state.items() if k.startswith("solver/")}
        sizes = np.cumsum([len(solver_state[f"L/{k:05d}"]) for k in range(_count_blocks(solver_state))])
        blocks = int(np.searchsorted(sizes, n - POLY_TERMS, side="right"))  # block rows within n centres
        solver_state = {k: v for k, v in solver_state.items() if k[:2] not in ("S/", "L/") or int(k[2:]) < blocks}
        solver_state.update(G=solver_state["G"][:, :n - POLY_TERMS], H=solver_state["H"][:n],
                            Pi=solver_state["Pi"][:n])
        solver = NullSpaceCholesky.from_state(solver_state)
    else:
        p = order[:POLY_TERMS]
        solver = FullLU(kernel_matrix(Z[p], Z[p]), poly_basis(Z[p]))
        if n > POLY_TERMS:
            rest = order[POLY_TERMS:]
            solver.extend(kernel_matrix(Z[rest], Z[p]), kernel_matrix(Z[rest], Z[rest]), poly_basis(Z[rest]))
    fit = GreedyFit(settings, points, values, shift, scale, order, solver, history=list(history))
    _Evaluator.attach(fit, device)
    if settings.update == "blocked":
        solver.colsum = np.abs(fit.evaluator.K[order, :n] if fit.evaluator.cached
                               else kernel_matrix(Z[order], Z[order])).sum(axis=0)
    fit.weights, fit.poly = solver.solve(values[order])
    fit.residual = fit.evaluator.residual(fit)
    return fit


def _count_blocks(solver_state):
    return sum(1 for k in solver_state if k.startswith("L/"))


def truncate_history(history, settings):
    """How many recorded iterations an uninterrupted fit with ``settings`` would also have made.

    Walks the history of a fit with the same centre sequence: iteration k is reused if the fit
    would not have stopped before it and its batch has the size the settings ask for.

    Returns
    -------
    int
        Number of leading history entries to keep (0 = start over).
    """
    keep = 0
    for k, rec in enumerate(history):
        expected = min(settings.batch, settings.max_centers) if k == 0 else \
            min(settings.batch, settings.max_centers - history[k - 1]["centers"])
        added = rec["centers"] - (POLY_TERMS if k == 0 else history[k - 1]["centers"])
        if k == 0:
            expected -= POLY_TERMS
        if added + rec["dropped"] != expected:
            break
        keep = k + 1
        if _stop_reason(rec, settings):
            break
    return keep


def iterate(fit, on_iteration=None):
    """Run the greedy loop until a stop criterion holds; returns the stop reason.

    ``on_iteration(fit, record)`` is called after every solve (for checkpoints and progress).
    """
    while True:
        if not fit.history or fit.history[-1]["centers"] != fit.n:
            _solve_and_record(fit, on_iteration)
        reason = _stop_reason(fit.history[-1], fit.settings)
        if reason:
            fit.stop_reason = reason
            return reason
        start = time.perf_counter()
        new = _select(fit)
        select_s = time.perf_counter() - start
        if len(new) == 0:
            fit.stop_reason = "exhausted"
            return fit.stop_reason
        start = time.perf_counter()
        dropped = _extend(fit, new)
        fit.pending = {"seconds_select": select_s, "seconds_update": time.perf_counter() - start,
                        "dropped": dropped}


def _solve_and_record(fit, on_iteration):
    start = time.perf_counter()
    fit.weights, fit.poly = fit.solver.solve(fit.values[fit.order])
    solve_s = time.perf_counter() - start
    start = time.perf_counter()
    fit.residual = fit.evaluator.residual(fit)
    eval_s = time.perf_counter() - start
    start = time.perf_counter()
    kappa = fit.solver.condition()
    cond_s = time.perf_counter() - start
    if not kappa <= MAX_CONDITION:
        raise FactorizationError(f"the fit's system is nearly singular at {fit.n} centres (condition number "
                                 f"{kappa:.2g}, beyond {MAX_CONDITION:g}): the constraint points lie near one "
                                 "quadric of space-time (a sphere scaled uniformly?)")
    err = np.linalg.norm(fit.residual, axis=1)
    pending = fit.pending or {"seconds_select": 0.0, "seconds_update": 0.0, "dropped": 0}
    record = {"iteration": len(fit.history), "centers": fit.n, "max_error": float(err.max()),
              "rms_error": float(np.sqrt(np.mean(err ** 2))), "condition": float(kappa),
              "seconds_evaluate": eval_s, "seconds_solve": solve_s, "seconds_condition": cond_s, **pending}
    fit.pending = None
    fit.history.append(record)
    log.info("iteration %d: %d centres, max error %.3g, rms %.3g, kappa %.2g (update %.2f s, "
             "solve %.2f s, evaluate %.2f s)", record["iteration"], fit.n, record["max_error"],
             record["rms_error"], kappa, record["seconds_update"], solve_s, eval_s)
    if on_iteration is not None:
        on_iteration(fit, record)


def _stop_reason(record, settings):
    if record["max_error"] < settings.eps:
        return "eps"
    if settings.eps_rms > 0 and record["rms_error"] < settings.eps_rms:
        return "rms"
    if record["centers"] >= settings.max_centers:
        return "max_centers"
    return ""


def _select(fit):
    """Indices of the constraints to add as centres next."""
    s = fit.settings
    err = np.linalg.norm(fit.residual, axis=1)
    err[fit.order] = -np.inf
    count = min(s.batch, s.max_centers - fit.n, len(err) - fit.n)
    if count <= 0:
        return np.zeros(0, dtype=np.int64)
    if s.selection == "worst":
        worst = np.argpartition(-err, count - 1)[:count]
        return worst[np.lexsort((worst, -err[worst]))]
    p = min(s.candidates, len(err) - fit.n)
    cand = np.argpartition(-err, p - 1)[:p]
    cand = cand[np.lexsort((cand, -err[cand]))]  # worst first, ties by index
    Z = fit.evaluator.Z
    return cand[farthest_points(Z[cand], min(count, p), [0])]


def _extend(fit, new):
    """Add constraints ``new`` as centres; returns how many were dropped as near-duplicates."""
    ev = fit.evaluator
    ev.fill(new, at=fit.n)
    keep = fit.solver.extend(ev.block(fit.order, new, at=fit.n).T, ev.block(new, new, at=fit.n),
                             poly_basis(ev.Z[new]), tol=fit.settings.pivot_tol)
    ev.commit(fit.n, keep)
    fit.order = np.concatenate([fit.order, new[keep]])
    return int(len(new) - keep.sum())


class _Evaluator:
    """Kernel values between the constraints and the centres, and the residual at every constraint.

    ``mode`` is chosen once per fit:

    * ``cached``: one Fortran-ordered (constraints x max_centres) array whose column blocks are
      filled as centres are added (each block contiguous, so only its own pages are touched); the
      residual is a matrix product. Used when it fits in ``settings.memory_bytes``.
    * ``opencl``: the residual is recomputed at every evaluation on the device
      (:class:`~posefix.spacetime.integration_opencl.FieldEvaluator`, agrees with numpy to ~1e-15).
    * ``numpy``: recomputed in chunks of constraints (the reference, and the fallback).
    """

    def __init__(self, fit, device=None):
        self.Z = (fit.points - fit.shift) / fit.scale
        self.poly = poly_basis(self.Z)
        self.cached = cache_fits(len(self.Z), fit.settings)
        self.K = np.empty((len(self.Z), fit.settings.max_centers), order="F") if self.cached else None
        self.device = None
        if not self.cached and device is not None:
            from posefix.spacetime.integration_opencl import FieldEvaluator
            self.device = FieldEvaluator(device, self.Z)
        self.mode = "cached" if self.cached else "opencl" if self.device else "numpy"

    @classmethod
    def attach(cls, fit, device=None):
        fit.evaluator = ev = cls(fit, device)
        log.info("residual evaluation: %s (%d constraints x %d centres at most, %.1f GB as a cache; budget %.1f GB)",
                 ev.mode, len(ev.Z), fit.settings.max_centers, len(ev.Z) * fit.settings.max_centers * 8e-9,
                 fit.settings.memory_bytes / 1e9)
        if ev.mode == "numpy":
            log.warning("WARNING: the kernel cache does not fit and no OpenCL device is available: the residual "
                        "is recomputed in numpy every iteration (slow; install pocl-opencl-icd)")
        if len(fit.order):
            ev.fill(fit.order, at=0)

    def fill(self, idx, at):
        """With the cache: write kernel(every constraint, constraints ``idx``) into columns ``at ..``."""
        if not self.cached:
            return
        out, C = self.K[:, at:at + len(idx)], self.Z[idx]
        for start in range(0, len(self.Z), _CHUNK):  # (m, chunk) C-order blocks are (chunk, m) F-order rows
            out[start:start + _CHUNK] = kernel(cdist(C, self.Z[start:start + _CHUNK], "sqeuclidean")).T

    def block(self, rows, idx, at):
        """Kernel between constraints ``rows`` and ``idx`` (filled at column ``at``), (len(rows), len(idx))."""
        if self.cached:
            return self.K[rows, at:at + len(idx)]
        return kernel_matrix(self.Z[rows], self.Z[idx])

    def commit(self, at, keep):
        """Keep the cache columns of the centres that were accepted (drop the others)."""
        if self.cached and not keep.all():
            self.K[:, at:at + keep.sum()] = self.K[:, at:at + len(keep)][:, keep]

    def residual(self, fit):
        """``values - f(points)`` at every constraint, (N, 3)."""
        if self.device is not None:
            return fit.values - self.device(self.Z[fit.order], fit.weights, fit.poly)
        fitted = self.poly @ fit.poly
        if self.cached:
            fitted += self.K[:, :fit.n] @ fit.weights
        else:
            C = self.Z[fit.order]
            for start in range(0, len(self.Z), _CHUNK):
                fitted[start:start + _CHUNK] += kernel_matrix(self.Z[start:start + _CHUNK], C) @ fit.weights
        return fit.values - fitted


def farthest_points(Z, count, start):
    """Greedy farthest-point order.

    Parameters
    ----------
    Z : (k, d) float
    count : int
        Number of points to return (including the start points).
    start : list of int
        Indices that begin the sequence.

    Returns
    -------
    (count,) int64
        Indices into ``Z``: each next one maximizes the distance to those before it (ties: lowest index).
    """
    chosen = list(dict.fromkeys(int(i) for i in start))[:count]
    dist = np.full(len(Z), np.inf)
    for i in chosen:
        dist = np.minimum(dist, ((Z - Z[i]) ** 2).sum(axis=1))
    while len(chosen) < count:
        i = int(np.argmax(dist))
        chosen.append(i)
        dist = np.minimum(dist, ((Z - Z[i]) ** 2).sum(axis=1))
    return np.array(chosen, dtype=np.int64)


def _diameter_pair(Z):
    """Two mutually distant points (double sweep from the first point): an approximate diameter."""
    a = int(np.argmax(((Z - Z[0]) ** 2).sum(axis=1)))
    b = int(np.argmax(((Z - Z[a]) ** 2).sum(axis=1)))
    return [a, b]
