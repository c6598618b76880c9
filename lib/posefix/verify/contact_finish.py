"""The contact finish of an integrated pose (``verify.finish: contact``): V_C onto its targets, the rest
toward its goal, through intersection-free shapes only (:mod:`posefix.mesh.contact_solver`).

1. **Start.** The integrated pose when it is intersection-free (no face intersects that does not in the
   reference; the exact detector). Where key frames pass through each other (S0 Fig. 9) it is not: then the
   start is the latest intersection-free sample of the integrated path lines, carried along the later
   samples by the contact solver, which holds the passing region on its intersection-free side.
2. **Goal.** ``V_C`` on its targets; the free region toward the target's positions with the integrated
   pose's shape (``free_goal: blend``, the default: the smoothness term keeps the displacement from the
   integrated pose, plus the ``V_C`` residual blended biharmonically into it, smooth, so the free region
   follows the target above the smoothing length and keeps the integrated pose's details below it: the
   target's crushed and stretched faces are not copied), on the target alone (``target``: the closest
   intersection-free shape to what the artist posed), or on the integrated pose plus the blended residual
   (``integrated``).
3. **Solve** with ``V_C`` weighted ``constrained_weight`` and the free region 1; the barrier keeps every
   new contact open.
4. **Exact V_C**: constrained vertices of no barrier pair are put exactly on their targets where CCD
   allows the (small) move. The constrained vertices of the reference's own intersecting faces (which the
   integrated pose inherits; the target may have undone them) are pulled with the free region's weight, as no
   intersection-free motion need reach them, and put on their targets in one step where the exact detector
   finds no new intersecting face, with the rings around them that this needs (flag 2), and the constrained
   vertices no longer in a barrier pair then are put on their targets too; where no ring does, they are pulled
   with V_C's weight from there.
5. **Check**: the exact detector checks the result. CCD bounds every step, but degenerate steps (a straight
   Newton step that crushes triangles to zero area, where Additive CCD warns of gaps below its precision)
   can miss a crossing; then the finish is reverted to the latest intersection-free sample of the path
   lines (``contact_reverted``) and says so.
"""

import logging
import time
from dataclasses import dataclass

import numpy as np

from posefix.mesh.contact_solver import WAYPOINT_TOLERANCE
from posefix.mesh.harmonic import biharmonic_extension
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.mesh.topology import grow_rings

log = logging.getLogger(__name__)

@dataclass(frozen=True)
class FinishSettings:
    """How the contact finish moves an integrated pose; the defaults are the pipeline's (config ``verify``).

    Attributes
    ----------
    free_goal : str
        ``blend`` (the target's positions with the integrated pose's shape below the smoothing length),
        ``target`` (the closest intersection-free shape to the pose) or ``integrated`` (the integrated free
        region plus the blended V_C residual). On the cat poses ``target`` copies the target's crushed faces
        where contacts press on them and the downstream Gauss-Newton check collapses them (cat-01, -02, -04);
        ``blend`` keeps them open, in a third to two thirds of the Newton iterations, for up to twice the
        free-region deviation (still below the snap finish's).
    constrained_weight : float
        Weight of ``V_C`` on its targets, relative to the free region's 1.
    untangle_rings : int
        Most rings grown (0, 1, 2, 4, ...) around the reference's own intersections where the target has undone
        them: the region then takes the target's positions (cat-09: 7 rings).
    """

    free_goal: str = "blend"
    constrained_weight: float = 1e6
    untangle_rings: int = 16


@dataclass
class FinishResult:
    """A pose after the contact finish.

    Attributes
    ----------
    X : (n, 3) float
    exact : (n,) bool
        Constrained vertices exactly on their targets.
    contact : (n,) bool
        Vertices of a barrier pair at the end (held off their goals by a contact).
    untangled : (n,) bool
        Vertices moved onto the target where it has undone the reference's own intersections.
    start : str
        ``integrated`` or ``sample <k>`` (the latest intersection-free sample, carried along the rest).
    metrics : dict
        Newton iterations (``contact_iterations``), convergence, start samples tracked, seconds.
    pairs : (P, 2) int
        Intersecting face pairs of ``X`` (the exact detector's check, reused by the verification).
    """

    X: np.ndarray
    exact: np.ndarray
    contact: np.ndarray
    untangled: np.ndarray
    start: str
    metrics: dict
    pairs: np.ndarray


def contact_finish(problem, solver, samples, settings=FinishSettings()):
    """Finish an integrated pose with the contact solver.

    Parameters
    ----------
    problem : posefix.verify.state.RepairProblem
        Target, ``V_C`` mask, adjacency and the reference's intersecting faces.
    solver : posefix.mesh.contact_solver.ContactSolver
        Built on the reference with its intersecting faces tolerated.
    samples : (S, n, 3) float
        The integrated path lines at their sample times, the reference first and the integrated pose last.
    settings : FinishSettings

    Returns
    -------
    FinishResult
    """
    t0 = time.perf_counter()
    start, label, tracked, iterations = _intersection_free_start(problem, solver, samples)
    goal, shape = _goal(problem, samples[-1], settings.free_goal)
    locked = _locked_vertices(problem)
    weights = np.where(problem.mask & ~locked, settings.constrained_weight, 1.0)
    result = solver.compute_pose(start, goal, weights, shape=shape)
    X, exact = _exact_constrained(problem, solver, result.X, result.contact, locked)
    X, exact, untangled = _untangled(problem, X, exact, locked, settings.untangle_rings)
    if untangled.any():  # contacts with the untangled region have changed: V_C away from the new ones is exact
        result.contact = solver.contact_vertices(solver.collisions(X), len(X))
        X, exact = _exact_constrained(problem, solver, X, result.contact, locked & ~exact)
    if (locked & ~exact).any():
        result, X, exact = _released(problem, solver, result, X, (goal, shape), settings.constrained_weight)
    pairs = self_intersecting_pairs(X, problem.F)
    reverted = bool((intersecting_faces(pairs, len(problem.F)) & ~problem.reference_faces).any())
    if reverted:
        X = samples[len(samples) - 1 - tracked]
        log.warning("contact finish: the result has new intersecting faces (a step CCD could not bound); reverted "
                    "to the latest intersection-free sample of the path lines")
        exact, untangled = problem.mask & (X == problem.V_tgt).all(axis=1), np.zeros(len(X), bool)
        result.contact, pairs = np.zeros(len(X), bool), self_intersecting_pairs(X, problem.F)
    log.info("contact finish from %s: %d Newton iterations (%s), %d of %d constrained vertices exact, %d vertices "
             "in contact", label, result.iterations, "converged" if result.converged else "not converged",
             exact.sum(), problem.mask.sum(), result.contact.sum())
    metrics = {"contact_iterations": result.iterations + iterations, "contact_converged": bool(result.converged),
               "contact_samples_tracked": tracked, "contact_vertices": int(result.contact.sum()),
               "contact_untangled": int(untangled.sum()), "contact_dhat_rel": solver.dhat / solver.d,
               "contact_reverted": reverted}
    return FinishResult(X, exact, result.contact, untangled, label,
                        metrics | {"contact_seconds": time.perf_counter() - t0}, pairs)


def new_faces(problem, X):
    """Faces of ``X`` that intersect and do not in the reference, (m,) bool (the exact detector)."""
    F = problem.F
    return intersecting_faces(self_intersecting_pairs(X, F), len(F)) & ~problem.reference_faces


def _intersection_free_start(problem, solver, samples):
    """(start, label, samples tracked, Newton iterations): the integrated pose if intersection-free, else the
    latest intersection-free sample carried along the later ones."""
    last = len(samples) - 1
    k = last
    while k > 0 and new_faces(problem, samples[k]).any():
        k -= 1
    if k == last:
        return samples[-1], "integrated", 0, 0
    result = solver.compute_path(samples[k], samples[k + 1:], WAYPOINT_TOLERANCE)
    log.info("contact finish: the integrated pose has new intersecting faces; samples %d-%d tracked from sample %d "
             "(%d Newton iterations)", k + 1, last, k, result.iterations)
    return result.X, f"sample {k}", last - k, result.iterations


def _goal(problem, X_int, free_goal):
    """``(goal (n, 3), shape (n, 3) or None)``: V_C on the target, the free region as ``free_goal`` says (shape:
    what the smoothness term keeps, None for the goal itself)."""
    if free_goal == "target":
        return problem.V_tgt.copy(), None
    mask = problem.mask
    integrated = X_int + biharmonic_extension(problem.A, problem.V_tgt - X_int, mask, ~mask)
    integrated[mask] = problem.V_tgt[mask]
    return (problem.V_tgt.copy(), integrated) if free_goal == "blend" else (integrated, None)


def _locked_vertices(problem):
    """Constrained vertices of the reference's own intersecting faces that the target has undone (they do not
    intersect there), (n,) bool. The integrated pose inherits those intersections, and no motion that keeps the
    intersection-free set need reach the targets of these vertices (cat: a paw through the other); pulled with
    V_C's weight they crushed the faces around them (cat-05: an edge 345x its length, V_C 1.4e-2 d off)."""
    locked = np.zeros(len(problem.mask), dtype=bool)
    locked[problem.F[problem.reference_faces & ~problem.target_faces].ravel()] = True
    return locked & problem.mask


def _untangled(problem, X, exact, locked, most):
    """Put the region of the reference's own intersections where the target has undone them onto the target.

    The vertices of the reference's intersecting faces that the target has undone (:func:`_locked_vertices`), grown
    by 0, 1, 2, 4, ... rings (at most ``most``) until the exact detector finds no new intersecting face, move onto
    their targets in one step (cat-05: 2 rings). Returns ``(X (n, 3), exact (n,) bool, untangled (n,) bool)``: unchanged when no ring works."""
    none = np.zeros(len(X), dtype=bool)
    if not (locked & ~exact).any():
        return X, exact, none
    seed = none.copy()
    seed[problem.F[problem.reference_faces & ~problem.target_faces].ravel()] = True
    for rings in sorted({0, most} | {2 ** k for k in range(most.bit_length()) if 2 ** k <= most}):
        region = grow_rings(seed, problem.A, rings)
        Y = X.copy()
        Y[region] = problem.V_tgt[region]
        if not new_faces(problem, Y).any():
            log.info("contact finish: the target has undone the reference's own intersections; %d vertices (%d "
                     "rings) take the target's positions", region.sum(), rings)
            return Y, exact | (region & problem.mask), region & (X != Y).any(axis=1)
    log.info("contact finish: %d constrained vertices of the reference's own intersecting faces stay off their "
             "targets (%d rings of the target intersect)", (locked & ~exact).sum(), most)
    return X, exact, none


def _released(problem, solver, result, X, goals, weight):
    """``(ContactResult, X (n, 3), exact (n,) bool)`` after pulling every constrained vertex with ``weight`` from
    ``X`` toward ``goals`` (:func:`_goal`): where the target's undoing of the reference's own intersections could not
    be taken (:func:`_untangled`), the vertices held back by :func:`_locked_vertices` still go as close to their
    targets as the barrier lets them (lion-08: V_C max 1.7e-3 d held back, 1.7e-4 d released). Iterations and
    seconds add up."""
    goal, shape = goals
    released = solver.compute_pose(X, goal, np.where(problem.mask, weight, 1.0), shape=shape)
    released.iterations += result.iterations
    released.seconds += result.seconds
    X, exact = _exact_constrained(problem, solver, released.X, released.contact, np.zeros(len(X), dtype=bool))
    return released, X, exact


def _exact_constrained(problem, solver, X, contact, locked):
    """``(X (n, 3), exact (n,) bool)``: the constrained vertices of ``X`` in no barrier pair (``contact`` (n,)
    bool) and not ``locked`` (n,) put exactly on their targets if CCD allows the move; ``exact``: the constrained
    vertices on their targets."""
    Y = X.copy()
    move = problem.mask & ~contact & ~locked
    Y[move] = problem.V_tgt[move]
    step = solver.collision_free_step(X, Y)
    if step < 1.0:
        log.info("contact finish: the exact V_C move would touch a contact (CCD step %.3f); kept the solver's", step)
        Y = X
    return Y, problem.mask & (Y == problem.V_tgt).all(axis=1)
