"""The pass-through fallback to the target (S0 §6, Fig. 9), followed by the untangling of new intersections.

Where key frames pass through each other, a flow cannot follow: it keeps the parts on their
sides, and vertices end far (``threshold``) from their targets (see :func:`pass_through_regions`
for the two triggers). Such regions, with the unconstrained parts they touch, are replaced by the
target when that adds no intersecting face the target does not have there (no seam between
copied and integrated parts). The target's own intersections in the copied region come back with
it, as in S0; they are reported separately. Then the faces that still newly intersect are
untangled (:mod:`posefix.verify.untangle`).
"""

import numpy as np

from posefix.mesh.intersections import new_pairs
from posefix.mesh.topology import grow_rings, selection_components
from posefix.verify.flags import REPLACED_PASS_THROUGH
from posefix.verify.state import RepairState
from posefix.verify.untangle import untangle


def fallback(problem, X, threshold, settings):
    """Replace regions of the repaired pose by the target where integration could not do its job.

    Parameters
    ----------
    problem : posefix.verify.state.RepairProblem
    X : (n, 3) float
        Integrated (and snapped) positions.
    threshold : float
        Distance (length units) beyond which a vertex counts as not having reached its target.
    settings : posefix.verify.sequence.RepairSettings
        ``ring`` (rings grown around the triggers and first tried around new intersections),
        ``max_rings`` (most rings tried around new intersections), ``repair_new`` (untangle them).

    Returns
    -------
    X : (n, 3) float
        Positions after the replacements.
    replaced : (n,) uint8
        Flags per vertex (:mod:`posefix.verify.flags`).
    new : (m,) bool
        New intersecting faces that remain.
    """
    state = RepairState(X, problem.F, problem.reference_faces)
    far = np.linalg.norm(X - problem.V_tgt, axis=1) > threshold
    for region in pass_through_regions(problem, far, settings.ring):
        trial = state.copy()
        trial.accept(trial.trial(region, problem.V_tgt), region, REPLACED_PASS_THROUGH)
        _cleanup(problem, trial, settings)
        seams = trial.new & ~problem.target_faces & ~state.new  # intersections neither before nor in the target
        state.log_trial("pass-through, target", region, trial.new, not seams.any())
        if not seams.any():
            state = trial
    _cleanup(problem, state, settings)
    return state.X, state.replaced, state.new


def _cleanup(problem, state, settings):
    if settings.repair_new:
        untangle(problem, state, settings.ring, settings.max_rings)


def transient_pairs(frame_pairs):
    """Face pairs that intersect in some intermediate key frame but not in the first or last one.

    Parameters
    ----------
    frame_pairs : list of (k_i, 2) int
        Intersecting pairs per key frame (sorted rows ``f < g``).

    Returns
    -------
    (p, 2) int64
    """
    ends = np.concatenate([frame_pairs[0], frame_pairs[-1]]).reshape(-1, 2)
    middle = np.concatenate([np.zeros((0, 2), dtype=np.int64)] + list(frame_pairs[1:-1])).reshape(-1, 2)
    return np.unique(new_pairs(middle, ends), axis=0)


def pass_through_regions(problem, far, ring):
    """Regions where integration did not reach the target, as connected components.

    Two kinds of seeds:

    * constrained vertices ending ``far`` from their targets, grown by ``ring`` rings;
    * unconstrained parts with a pair of faces that intersect only in intermediate key frames
      (:func:`transient_pairs`), some vertex ending far from its target, and no face intersecting
      in the target: key frames pass through each other where the target is clean (S0 Fig. 9),
      and the flow left the part behind.

    The unconstrained components the seeds touch are added (the parts that were carried along),
    and the region is closed under the target's intersecting pairs (a part the copied target
    region intersects in the target is copied too, so that no seam appears between them).

    Parameters
    ----------
    problem : posefix.verify.state.RepairProblem
    far : (n,) bool
        Vertices that did not reach their targets.
    ring : int

    Returns
    -------
    list of (k_i,) int64
        Vertex indices per region.
    """
    F, A, mask = problem.F, problem.A, problem.mask
    free = selection_components(~mask, A)
    seeds = _seeds(problem, free, far, ring)
    if not seeds.any():
        return []
    target_pairs = problem.frame_pairs[-1]
    region = _closure(problem, free, seeds)
    return selection_components(region, A, np.stack([F[target_pairs[:, 0], 0], F[target_pairs[:, 1], 0]], axis=1))


def _seeds(problem, free, far, ring):
    """Seeds of :func:`pass_through_regions`, (n,) bool; ``free`` the unconstrained components."""
    F, mask = problem.F, problem.mask
    seeds = grow_rings(mask & far, problem.A, ring)
    transient = transient_pairs(problem.frame_pairs)
    in_transient = np.zeros(len(mask), dtype=bool)
    in_transient[F[transient].ravel()] = True
    for component in free:
        inside = np.zeros(len(mask), dtype=bool)
        inside[component] = True
        clean = not problem.target_faces[inside[F].any(axis=1)].any()
        if clean and in_transient[component].any() and far[component].any():
            seeds[component] = True
    return seeds


def _closure(problem, free, seeds):
    """``seeds`` grown by the unconstrained components they touch and the target's intersecting
    partners of their faces, until nothing more is added, (n,) bool."""
    F, A, mask = problem.F, problem.A, problem.mask
    target_pairs = problem.frame_pairs[-1]
    label = np.full(len(mask), -1)
    for c, component in enumerate(free):
        label[component] = c
    region = seeds.copy()
    while True:
        touched = np.unique(label[grow_rings(region, A, 1) & ~mask])
        partners = target_pairs[region[F[target_pairs]].any(axis=2).any(axis=1)]
        touched = np.union1d(touched, np.unique(label[F[partners].ravel()]))
        grown = region.copy()
        for c in touched[touched >= 0]:
            grown[free[c]] = True
        grown[F[partners].ravel()] = True
        if (grown == region).all():
            return region
        region = grown
