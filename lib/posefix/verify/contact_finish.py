"""The contact finish of an integrated pose (``verify.finish: contact``): V_C onto its targets, the rest
toward its goal, through intersection-free shapes only (:mod:`posefix.mesh.contact_solver`).

1. **Start.** The integrated pose when it is intersection-free (no face intersects that does not in the
   reference; the exact detector). Where key frames pass through each other (S0 Fig. 9) it is not: then the
   start is the latest intersection-free sample of the integrated path lines, carried along the later
   samples by the contact solver, which holds the passing region on its intersection-free side.
2. **Goal.** ``V_C`` on its targets; the free region under an elastic energy (``free_goal: elastic``, the
   default): a discrete shell (log-strain stretching, bending) and log face areas, invariant to rigid motion,
   whose rest state is the target's edge lengths and face areas clipped to within ``rest_limit`` of the
   reference's, and its dihedral angles where its faces are within that limit (the reference's elsewhere), plus
   a weak pull (``elastic_weight``) toward the target's positions. A part that turns keeps its shape, and a contact's push bends and slides the surface instead of
   crushing it. ``V_C`` away from contacts is pinned on its targets (not an unknown) when CCD allows the move.
   The positional goals stay for comparison: the target's positions with the integrated pose's shape
   (``blend``: the smoothness term keeps the displacement from the integrated pose, plus the ``V_C`` residual
   blended biharmonically into it), the target alone (``target``), or the integrated pose plus the blended
   residual (``integrated``).
3. **Solve** with ``V_C`` weighted ``constrained_weight`` and the free region ``elastic_weight`` (elastic) or 1
   (positional); the barrier keeps every new contact open. The elastic finish starts from the intersection-free
   candidate of lower energy (the integrated pose or the key frames tracked, per free region), and solves again
   from the other where the result would not make the pose *ok* (:func:`_lower_energy_result`).
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
from dataclasses import dataclass, field

import numpy as np
from scipy.sparse.csgraph import connected_components

from posefix.mesh.contact_solver import WAYPOINT_TOLERANCE
from posefix.mesh.distortion import DISTORTED_SHARE, DISTORTION_LIMIT, SEVERE, distorted_faces
from posefix.mesh.harmonic import biharmonic_extension
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.mesh.shells import rest_elastic_energy
from posefix.mesh.topology import grow_rings

log = logging.getLogger(__name__)

EXACT_ROUNDS = 16
"""Most rounds of :func:`_exact_constrained`: each holds back the vertices whose move collides, then those of the
pairs with a vertex held back (their moves changed); then the move is given up (kids-0001's second start: past the
22,513 vertices that would move farther than an edge, 6 rounds held back 250, 93, 47, 16, 17 and 5 of 27,428)."""

@dataclass(frozen=True)
class FinishSettings:
    """How the contact finish moves an integrated pose; the defaults are the pipeline's (config ``verify``).

    Attributes
    ----------
    free_goal : str
        ``elastic`` (a discrete shell and face areas with the target's shape within ``rest_limit`` of the
        reference as rest state, pulled weakly toward the target's positions), or a positional goal: ``blend`` (the target's positions with the integrated pose's shape
        below the smoothing length), ``target`` (the closest intersection-free shape to the pose) or
        ``integrated`` (the integrated free region plus the blended V_C residual). The positional goals are not
        invariant to rotation: where a part turns or a contact presses they crush and stretch faces (demo-01:
        29 faces beyond 4x with ``blend``, 0 with ``elastic``).
    constrained_weight : float
        Weight of ``V_C`` on its targets, relative to the free region's 1.
    untangle_rings : int
        Most rings grown (0, 1, 2, 4, ...) around the reference's own intersections where the target has undone
        them: the region then takes the target's positions (cat-09: 7 rings).
    elastic_weight : float
        ``elastic``: weight of the free region's pull toward the target's positions (the elastic energy's is 1).
        With 0.1 the demo's free region lay 1.22x farther from the target than the contact peer's (free mean
        1.29e-2 against 1.06e-2 d); 0.3: 1.16x, with no more distorted faces; 1.0: 1.09x, 4 distorted faces.
    bending : float
        ``elastic``: bending stiffness ``k_b`` of the shell (stretching's and areas' are 1). On the demo's folds
        1e-3 lets the compressed skin wrinkle, and the downstream Gauss-Newton check then collapses a triangle
        toward demo-01 (converged toward 2 of 4 poses); 0.1 kept the fold smooth (3 of 4) until the rest limit of 3
        (then 2 of 4); 1.0 does (3 of 4: demo-04 collapses with every setting tried), for lion 28 distorted faces
        instead of 22 and a free mean of 1.7e-3 d instead of 1.3e-3 (the contact peer: 82, 2.5e-3).
    rest_limit : float
        ``elastic``: the rest state's edge lengths and face areas are the target's clipped to within this ratio of
        the reference's, below ``summary.distortion_limit`` (4): a rest state at that limit leaves the faces that
        the target crushes just beyond it once contacts and the pull press (lion: 50 distorted faces with a rest
        limit of 4, 22 with 3, 5 % more free-region deviation). With 3, faces that the target crushes 20-30x
        (camel's and the demo's folds) were pressed just past 4x of the reference: camel 5 distorted faces against
        the contact peer's 2, the demo 7; with 2 (and ``elastic_weight`` 0.3): 0 and 0, lion 23, cat 27.
    tracked_iterations : int
        ``elastic``: Newton iterations at most per key frame of the tracked start (:func:`_lower_energy_start`).
        V_C weighted ``constrained_weight`` presses into the contacts, where Newton creeps (lion-08: 174
        iterations on the last key frame) and crushes faces that the elastic solve then has to restore: with 20,
        lion's 9 poses have 50 faces beyond the limit instead of 60, lion-08 takes 29 s instead of 81 s; with 10,
        lion-07 has 12 instead of 7.
    second_iterations : int
        ``elastic``: Newton iterations at most of the solve from the candidate start not taken, where the first
        result would not make the pose *ok* (:func:`_lower_energy_result`). A start that needs many more than the
        first is creeping along contacts: kids-0001's took 70 at ``--threads 1`` and 181 in a run at 2 threads (450 s
        of the finish's 1,041 s), to results with 103 and 81 faces beyond 10x against the first's 34 and 32, and
        was thrown away.
    """

    free_goal: str = field(default="elastic", metadata={
        "help": "contact finish: what moves the free region: elastic (a discrete shell and face areas with the "
                "target's shape as rest state, pulled toward the target), or a positional goal: blend (the target's "
                "positions with the integrated pose's shape below the smoothing length), target, or integrated (the "
                "integrated pose plus the blended V_C residual)", "choices": ("elastic", "blend", "target", "integrated")})
    constrained_weight: float = field(default=1e6, metadata={
        "help": "contact finish: weight of V_C on its targets relative to the free region's", "exclusiveMinimum": 0})
    untangle_rings: int = field(default=16, metadata={
        "help": "contact finish: most rings (0, 1, 2, 4, ...) around the reference's own intersections that the "
                "target has undone, put onto the target", "minimum": 0})
    elastic_weight: float = field(default=0.3, metadata={
        "help": "elastic finish: weight of the free region's pull toward the target's positions (the elastic energy's "
                "is 1)", "exclusiveMinimum": 0})
    bending: float = field(default=1.0, metadata={
        "help": "elastic finish: bending stiffness k_b of the shell (stretching's and areas' are 1)", "minimum": 0})
    rest_limit: float = field(default=2.0, metadata={
        "help": "elastic finish: the rest state's edge lengths and face areas are the target's clipped to within this "
                "ratio of the reference's (below summary.distortion_limit, where a face counts as distorted)",
        "exclusiveMinimum": 1})
    tracked_iterations: int = field(default=20, metadata={
        "help": "elastic finish: Newton iterations at most per key frame of the start tracked through the key frames",
        "minimum": 1})
    second_iterations: int = field(default=40, metadata={
        "help": "elastic finish: Newton iterations at most of the second solve, from the start not taken, where the "
                "first result would not make the pose ok", "minimum": 1})


@dataclass(frozen=True)
class _Motion:
    """How the finish moves the free region: toward ``goal`` (n, 3), keeping ``shape`` (n, 3) or None (positional)
    or under the ``elastic`` energy (an ElasticEnergy, or None), with the free region's weight ``free_weight``."""

    goal: np.ndarray
    shape: np.ndarray
    elastic: object
    free_weight: float

    def solve(self, solver, start, heavy, weight, pinned, max_iterations=None):
        """The contact solver's result from ``start`` with the vertices ``heavy`` (n,) bool weighted ``weight`` and the
        others ``free_weight``; ``pinned`` (n,) bool stay where they are (elastic only, else None); at most
        ``max_iterations`` Newton iterations (the solver's setting by default)."""
        weights = np.where(heavy, weight, self.free_weight)
        if self.elastic is None:
            return solver.compute_pose(start, self.goal, weights, shape=self.shape, max_iterations=max_iterations)
        return solver.compute_elastic(start, self.goal, weights, self.elastic, pinned, max_iterations)


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


def contact_finish(problem, solver, samples, settings=FinishSettings(), frames=None):
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
    frames : (K, n, 3) float, optional
        The key frames, the reference first and the target last: the elastic finish tracks them for a second
        candidate start (:func:`_lower_energy_start`).

    Returns
    -------
    FinishResult
    """
    t0 = time.perf_counter()
    motion, locked = _motion(problem, samples[-1], settings), _locked_vertices(problem)
    result, label, tracked, iterations = _solved(problem, solver, (samples, frames), motion, locked, settings)
    X, exact = _exact_constrained(problem, solver, result.X, result.contact, locked)
    X, exact, untangled = _untangled(problem, X, exact, locked, settings.untangle_rings)
    if untangled.any():  # contacts with the untangled region have changed: V_C away from the new ones is exact
        result.contact = solver.contact_vertices(solver.collisions(X), len(X))
        X, exact = _exact_constrained(problem, solver, X, result.contact, locked & ~exact)
    if (locked & ~exact).any() or (untangled.any() and motion.elastic is not None):
        result, X, exact = _released(problem, solver, result, X, motion, settings.constrained_weight, untangled)
    X, _ = solver.keep_gap(X, ~exact)  # a file of float32 positions rounds them: no pair so close that it crosses
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
               "contact_start": label, "contact_samples_tracked": tracked, "contact_vertices": int(result.contact.sum()),
               "contact_untangled": int(untangled.sum()), "contact_dhat_rel": solver.dhat / solver.d,
               "contact_reverted": reverted}
    return FinishResult(X, exact, result.contact, untangled, label,
                        metrics | {"contact_seconds": time.perf_counter() - t0}, pairs)


def _solved(problem, solver, paths, motion, locked, settings):
    """``(ContactResult, start label, samples tracked, Newton iterations of the start)``: the solve from
    :func:`_start`'s start (``paths``: samples and key frames), and from the candidate not taken too where the first
    would not make the pose *ok*: not converged, or its free region out of shape at the status's
    :data:`~posefix.mesh.distortion.DISTORTION_LIMIT` (:func:`_lower_energy_result`). At the rest state's bound
    instead (``rest_limit``, 2), the second solve ran on all of cat's 9 poses and 5 of lion's 9, where it runs on
    none now: verify took 407 s and 232 s for them, now 257 s and 176 s, with the same statuses; 31 faces beyond 4x
    on cat instead of 27, and lion-01's worst edge ratio against the nearer of target and reference 4.96 instead of
    2.91 (the contact repair's against the target: 3.05)."""
    start, label, tracked, iterations, other = _start(problem, solver, paths, motion, locked, settings)
    heavy = problem.mask & ~locked
    start, pinned = _pinned(problem, solver, start, locked) if motion.elastic is not None else (start, None)
    result = motion.solve(solver, start, heavy, settings.constrained_weight, pinned)
    if other is not None and _not_ok(problem, result):
        result, label = _lower_energy_result(problem, solver, motion, (result, label), other,
                                             (heavy, locked, settings.constrained_weight, settings.second_iterations))
    return result, label, tracked, iterations


def new_faces(problem, X):
    """Faces of ``X`` that intersect and do not in the reference, (m,) bool (the exact detector)."""
    F = problem.F
    return intersecting_faces(self_intersecting_pairs(X, F), len(F)) & ~problem.reference_faces


def _latest_free_sample(problem, samples):
    """The index of the latest sample of ``samples`` (S, n, 3) with no new intersecting face (0: the reference)."""
    k = len(samples) - 1
    while k > 0 and new_faces(problem, samples[k]).any():
        k -= 1
    return k


def _intersection_free_start(problem, solver, samples, k):
    """(start, label, samples tracked, Newton iterations): the integrated pose if intersection-free (``k``, the
    :func:`_latest_free_sample`, is the last), else sample ``k`` carried along the later ones."""
    last = len(samples) - 1
    if k == last:
        return samples[-1], "integrated", 0, 0
    result = solver.compute_path(samples[k], samples[k + 1:], WAYPOINT_TOLERANCE)
    log.info("contact finish: the integrated pose has new intersecting faces; samples %d-%d tracked from sample %d "
             "(%d Newton iterations)", k + 1, last, k, result.iterations)
    return result.X, f"sample {k}", last - k, result.iterations


def _start(problem, solver, paths, motion, locked, settings):
    """``(start (n, 3), label, samples tracked, Newton iterations, other)``.

    :func:`_intersection_free_start` of the path lines (``paths``: (samples (S, n, 3), key frames (K, n, 3) or
    None)); the elastic finish takes instead the key frames tracked (``settings``: FinishSettings) where their energy
    is lower (:func:`_lower_energy_start`), with the constrained vertices in no barrier pair and not ``locked`` on
    their targets where CCD allows the move (:func:`_exact_constrained`). ``other``: the candidate not taken
    (start and label; :func:`_lower_energy_result`), or None.

    Where no sample after the reference is intersection-free, nothing of the integration is left to keep: the
    elastic finish starts from the tracked key frames alone, and the reference is not tracked along the path lines
    as well (kids-0001: 405 of verify's 821 s, for a candidate whose energy was higher)."""
    samples, frames = paths
    k = _latest_free_sample(problem, samples)
    if motion.elastic is None or frames is None:
        return *_intersection_free_start(problem, solver, samples, k), None
    if k == 0:
        result = _tracked_key_frames(problem, solver, frames, settings)
        log.info("contact finish: no sample after the reference is intersection-free; the start is the key frames "
                 "tracked (%d Newton iterations)", result.iterations)
        return result.X, "tracked", len(samples) - 1, result.iterations, None
    start, label, tracked, iterations = _intersection_free_start(problem, solver, samples, k)
    start, label, iterations, other = _lower_energy_start(problem, solver, frames, motion,
                                                          (start, label, iterations), settings)
    return start, label, tracked, iterations, other


def _pinned(problem, solver, start, locked):
    """``(start (n, 3), pinned (n,) bool)``: the vertices the elastic finish pins from ``start``, the constrained
    ones in no barrier pair and not ``locked``, put on their targets where CCD allows (:func:`_exact_constrained`)."""
    contact = solver.contact_vertices(solver.collisions(start), len(start))
    return _exact_constrained(problem, solver, start, contact, locked)


def _pushed(problem, X, limit):
    """Faces of ``X`` (n, 3) with a free vertex beyond ``limit`` (a distortion ratio) against both the target
    and the reference: contacts pushed them there, (m,) bool."""
    free = (~problem.mask[problem.F]).any(axis=1)
    return distorted_faces(X, [problem.V_tgt, problem.V_ref], problem.F, limit) & free


def _not_ok(problem, result):
    """Whether the ContactResult ``result`` would not make the pose *ok*: not converged, or :func:`_out_of_shape` at
    :data:`~posefix.mesh.distortion.DISTORTION_LIMIT`."""
    return not result.converged or _out_of_shape(problem, result.X, DISTORTION_LIMIT)


def _out_of_shape(problem, X, limit):
    """Whether contacts pushed the free region of ``X`` (n, 3) out of shape: more than
    :data:`~posefix.mesh.distortion.DISTORTED_SHARE` of the faces :func:`_pushed` beyond ``limit``, or one beyond
    :data:`~posefix.mesh.distortion.SEVERE`."""
    return _pushed(problem, X, limit).sum() > DISTORTED_SHARE * len(problem.F) or _pushed(problem, X, SEVERE).any()


def _lower_energy_result(problem, solver, motion, first, other, solve):
    """``(ContactResult, label)``: of the solve from the start taken (``first``: its result and label) and from the
    candidate not taken (``other``: start and label), the converged one, then the one with fewer faces pushed beyond
    :data:`~posefix.mesh.distortion.SEVERE` (:func:`_pushed`), then the one of lower energy (the finish's, less the
    barrier). Converged first: a solve stopped by its iteration cap is still on its way, V_C off its targets
    (kids-0001's second solve after 40 iterations, in a run at 2 threads: 23 faces beyond 10x against the first's
    34, and an energy of 5.0e4 against 0.29), and a creeping solve's lower energy is no better shape (cat-08: 400 Newton iterations
    along a contact to an energy 16 % lower, and the pose was *check*).

    Each start decides on which side of a contact each part ends (:func:`_lower_energy_start`), and an energy
    measured at the start cannot tell where a part will catch on another on the way to its target: a lion pose read
    from a float32 file had a vertex dragged 0.13 d off its target, its edges 46x their length, 4 faces beyond
    10x, from the start of lower energy; from the other start none, and an energy 11 % higher (tiny faces weigh
    little in it). ``solve``: (heavy (n,) bool, locked (n,) bool, their weight) as the first solve's, and the second
    solve's most Newton iterations (``FinishSettings.second_iterations``). Iterations and seconds add up."""
    (result, label), (start, other_label) = first, other
    heavy, locked, weight, most = solve
    start, pinned = _pinned(problem, solver, start, locked)
    second = motion.solve(solver, start, heavy, weight, pinned, most)
    goal_weights = np.where(heavy, weight, motion.free_weight)
    scores = [(not r.converged, int(_pushed(problem, r.X, SEVERE).sum()),
               solver.elastic_energy(r.X, motion.goal, goal_weights, motion.elastic)) for r in (result, second)]
    log.info("contact finish: not ok from the %s start (%sconverged, %d faces beyond %gx, energy %.4g); from the %s "
             "start %sconverged, %d, %.4g", label, "not " * scores[0][0], scores[0][1], SEVERE, scores[0][2],
             other_label, "not " * scores[1][0], scores[1][1], scores[1][2])
    kept, label = (second, f"{other_label} (second start)") if scores[1] < scores[0] else (result, label)
    kept.iterations, kept.seconds = result.iterations + second.iterations, result.seconds + second.seconds
    return kept, label


def _lower_energy_start(problem, solver, frames, motion, integrated, settings):
    """``(start, label, Newton iterations, other)``: of the intersection-free candidates, the one of lower energy (the
    elastic finish's, less the barrier, over the free region: elastic energy and pull toward the target), per
    connected free region where the exact detector allows (:func:`_regional_start`): the integrated one
    (``integrated``: :func:`_intersection_free_start`'s start, label and iterations) or the key frames ``frames``
    (K, n, 3) tracked by the contact solver with V_C weighted ``settings.constrained_weight``, at most
    ``settings.tracked_iterations`` Newton iterations per key frame (label ``tracked``). An elastic energy cannot
    pull a region back through a contact, so the start decides on which side of one it ends: where the integrated
    path lines follow a neighbouring part's motion (a finger caught on the wrong side of the next), the tracked key
    frames do not; the pull toward the target counts, as a region caught on the wrong side may be as unstretched
    as one on the right side. ``other``: (start, label) of the whole candidate not taken (the integrated one when
    the start is mixed)."""
    X, label, iterations = integrated
    result = _tracked_key_frames(problem, solver, frames, settings)
    free = np.where(problem.mask, 0.0, motion.free_weight)
    regions = _free_regions(problem)
    energies = [solver.elastic_energy(Y, motion.goal, free, motion.elastic, regions) for Y in (X, result.X)]
    log.info("contact finish: energy of the %s start %.4g, of the tracked key frames %.4g (%d Newton iterations, "
             "%d free regions)", label, energies[0].sum(), energies[1].sum(), result.iterations, len(energies[0]))
    start, taken = _regional_start(problem, solver, (X, label), result.X, energies, regions)
    other = (X, label) if taken.startswith("tracked") else (result.X, "tracked")
    return start, taken, iterations + result.iterations, other


def _tracked_key_frames(problem, solver, frames, settings):
    """The ContactResult of the key frames ``frames`` (K, n, 3) tracked by the contact solver from the reference, V_C
    weighted ``settings.constrained_weight`` (FinishSettings), at most ``settings.tracked_iterations`` Newton
    iterations per key frame."""
    return solver.compute_path(frames[0], frames[1:], weights=np.where(problem.mask, settings.constrained_weight, 1.0),
                               max_iterations=settings.tracked_iterations)


def _free_regions(problem):
    """The connected free regions (``~problem.mask``, along the mesh's edges): (n,) int, -1 on V_C."""
    free = ~problem.mask
    regions = np.full(len(free), -1)
    if free.any():
        regions[free] = connected_components(problem.A[free][:, free], directed=False)[1]
    return regions


def _regional_start(problem, solver, integrated, tracked, energies, regions):
    """``(start, label)``: the tracked start ``tracked`` (n, 3) with the free regions where the integrated start
    (``integrated``: positions and label) has the lower energy (``energies``: per region, integrated's and
    tracked's; ``regions``: :func:`_free_regions`) taken from it, where the result has no new intersecting face (the exact detector) and no
    non-tolerated pair in contact; else the candidate of lower total energy."""
    X, label = integrated
    lower = energies[0] < energies[1]
    if lower.any() and not lower.all():
        mixed = tracked.copy()
        take = (regions >= 0) & lower[regions]
        mixed[take] = X[take]
        if not new_faces(problem, mixed).any() and solver.min_distance(mixed) > 0.0:
            return mixed, f"tracked, {lower.sum()} of {len(lower)} free regions {label}"
    if energies[1].sum() < energies[0].sum():
        return tracked, "tracked"
    return X, label


def _motion(problem, X_int, settings):
    """The :class:`_Motion` of ``settings.free_goal``: V_C on the target, the free region as the goal says (module
    docstring, 2.); ``X_int`` (n, 3) the integrated pose."""
    if settings.free_goal == "elastic":
        elastic = rest_elastic_energy(problem.V_ref, problem.F, problem.V_tgt, settings.rest_limit,
                                      settings.bending)
        return _Motion(problem.V_tgt.copy(), None, elastic, settings.elastic_weight)
    if settings.free_goal == "target":
        return _Motion(problem.V_tgt.copy(), None, None, 1.0)
    mask = problem.mask
    integrated = X_int + biharmonic_extension(problem.A, problem.V_tgt - X_int, mask, ~mask)
    integrated[mask] = problem.V_tgt[mask]
    if settings.free_goal == "blend":
        return _Motion(problem.V_tgt.copy(), integrated, None, 1.0)
    return _Motion(integrated, None, None, 1.0)


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


def _released(problem, solver, result, X, motion, weight, untangled):
    """``(ContactResult, X (n, 3), exact (n,) bool)`` after pulling every constrained vertex with ``weight`` from
    ``X`` as ``motion`` (:func:`_motion`) moves it: where the target's undoing of the reference's own intersections
    could not be taken (:func:`_untangled`), the vertices held back by :func:`_locked_vertices` still go as close to
    their targets as the barrier lets them (lion-08: V_C max 1.7e-3 d held back, 1.7e-4 d released). The elastic
    finish pins the ``untangled`` (n,) bool vertices on the target too, and its free region relaxes around them
    (cat-09: the faces between the untangled region and the rest were stretched 6-9x). Iterations and seconds add
    up."""
    exact = problem.mask & (X == problem.V_tgt).all(axis=1)
    released = motion.solve(solver, X, problem.mask, weight, None if motion.elastic is None else exact | untangled)
    released.iterations += result.iterations
    released.seconds += result.seconds
    X, exact = _exact_constrained(problem, solver, released.X, released.contact, np.zeros(len(X), dtype=bool))
    return released, X, exact


def _exact_constrained(problem, solver, X, contact, locked):
    """``(X (n, 3), exact (n,) bool)``: the constrained vertices of ``X`` in no barrier pair (``contact`` (n,)
    bool) and not ``locked`` (n,) put exactly on their targets where CCD allows the move; ``exact``: the constrained
    vertices on their targets.

    The vertices whose move would collide (:meth:`~posefix.mesh.contact_solver.ContactSolver.blocked_vertices`)
    stay, and the others move, again until CCD allows the whole move (kids-0001: the tracked start's move of 48,885
    constrained vertices touched a contact at 14 % of the way, and none was pinned; 385 held back in 3 rounds). A
    vertex that would move farther than the reference's mean edge length stays too: its move sweeps past millions of
    pairs (kids-0001's second start, V_C up to 16 edge lengths off: 14 million, 100 s to check; 27,000 of 49,941
    vertices pinned in 2-6 s without the 22,513 far ones)."""
    move = problem.mask & ~contact & ~locked
    Y = X.copy()
    Y[move] = problem.V_tgt[move]
    changed = (X != Y).any(axis=1)  # the vertices whose pairs' moves are to check
    for k in range(EXACT_ROUNDS):
        if solver.collision_free_step(X, Y) == 1.0:
            break
        far = np.linalg.norm(Y - X, axis=1) > solver.edge_length if k == 0 else None
        if k == 0 and far.any():  # a move longer than an edge sweeps past too many pairs to check one by one
            Y[far] = X[far]
            changed = (X != Y).any(axis=1)
            continue
        blocked = solver.blocked_vertices(X, Y, changed)
        log.info("contact finish: the exact move of %d constrained vertices would touch a contact; %d held back",
                 (X != Y).any(axis=1).sum(), blocked.sum())
        if not blocked.any():
            Y = X
            break
        Y[blocked], changed = X[blocked], blocked  # only the pairs of the vertices held back move otherwise now
    else:
        Y = X
    return Y, problem.mask & (Y == problem.V_tgt).all(axis=1)
