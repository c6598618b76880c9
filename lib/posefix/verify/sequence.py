"""The repair of one integrated pose, as stage ``verify`` runs it: a finish that puts ``V_C`` on its targets,
then the verification.

Two finishes (config ``verify.finish``): ``contact`` (:func:`finish_pose`, :mod:`posefix.verify.contact_finish`:
the contact solver moves the integrated pose, and no new intersection can form) and ``snap``
(:func:`repair_pose`: snap, fallback, snap again):

1. **Snap** (:mod:`posefix.verify.reproduce`): constrained vertices within ``reach`` of their
   targets, ``reach = max(threshold, fallback_fit * fit max error)``, are put exactly on them;
   the residual is blended into the rest. First, so that the fallback works on the corrected pose:
   constrained vertices that could not be snapped (that would add intersections) and stay beyond
   ``threshold = fallback_eps * eps`` trigger the pass-through fallback.
2. **Fallback** (:mod:`posefix.verify.fallback`): pass-through regions copied from the target,
   new intersections untangled.
3. **Snap again**: what the fallback untangled may now be snapped.
4. **Verify**: intersecting faces of the repaired pose, new ones (not in the reference), and the
   deviation from the target over ``V_C`` and the rest.
"""

import logging
import time
from dataclasses import dataclass, field, fields

import numpy as np

from posefix.mesh.contact_solver import ContactSettings, ContactSolver
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.verify.contact_finish import FinishSettings, contact_finish
from posefix.verify.deviation import deviation
from posefix.verify.fallback import fallback
from posefix.verify.flags import CONTACT, PUSHED, REPLACED_NEW_INTERSECTION, REPRODUCED, flag_counts
from posefix.verify.reproduce import reproduce_targets

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class RepairSettings:
    """How a pose is repaired; the defaults are the pipeline's (config ``verify``).

    Attributes
    ----------
    finish : str
        ``snap`` (this sequence) or ``contact`` (:func:`finish_pose`; the other fields do not apply).
    fallback_eps : float
        Constrained vertices farther than ``fallback_eps * eps`` from their targets (after the
        snap) did not reach them: pass-through triggers.
    fallback_fit : float
        Constrained vertices within ``max(that, fallback_fit * the fit's max error)`` of their
        targets are snapped onto them.
    ring : int
        Rings grown around fallback triggers (and first tried around new intersections).
    max_rings : int
        Most rings tried around new intersections.
    repair_new : bool
        Untangle new intersections.
    reproduce : bool
        Snap; False keeps the integrated positions of ``V_C``.
    """

    finish: str = field(default="contact", metadata={
        "help": "how V_C reaches its targets: contact (the contact solver moves it there, no new intersection can "
                "form) or snap (snap V_C, fall back to the target and untangle)", "choices": ("contact", "snap")})
    fallback_eps: float = field(default=100.0, metadata={
        "help": "snap finish: vertices farther than this many eps from their targets have not reached them",
        "exclusiveMinimum": 0})
    fallback_fit: float = field(default=2.0, metadata={
        "help": "snap finish: constrained vertices within this many fit max errors (at least the threshold above) of "
                "their targets are put on them", "minimum": 0})
    ring: int = field(default=1, metadata={"help": "snap finish: rings grown around fallback triggers (first attempt)",
                                           "minimum": 0})
    max_rings: int = field(default=6, metadata={"help": "snap finish: most rings tried around new intersections",
                                                "minimum": 0})
    repair_new: bool = field(default=True, metadata={
        "help": "snap finish: replace regions with new intersections by the target and untangle them"})
    reproduce: bool = field(default=True, metadata={
        "help": "snap finish: put the constrained vertices exactly on their targets (else keep the integrated "
                "positions)"})


@dataclass
class RepairResult:
    """A repaired pose and what verify measured on it (shapes as in ``verify.h5``).

    Attributes
    ----------
    X : (n, 3) float
        Repaired positions.
    replaced : (n,) uint8
        Flags per vertex (:mod:`posefix.verify.flags`).
    pairs : (P, 2) int64
        Intersecting face pairs of the repaired pose.
    faces, new : (m,) bool
        Intersecting faces of the repaired pose, and those not intersecting in the reference.
    deviation, integrated_deviation : (n,) float
        ``|X - target| / d`` per vertex, after the repair and before it.
    summary, integrated : dict
        Their summaries (:func:`posefix.verify.deviation.deviation`).
    seconds : dict
        Wall seconds of ``reproduce`` (both snaps) and ``fallback``, or ``contact``; and ``verify``.
    metrics : dict
        The scalar results of ``verify.h5`` (``docs/artifacts.md``).
    """

    X: np.ndarray
    replaced: np.ndarray
    pairs: np.ndarray
    faces: np.ndarray
    new: np.ndarray
    deviation: np.ndarray
    integrated_deviation: np.ndarray
    summary: dict
    integrated: dict
    seconds: dict
    metrics: dict = None


def repair_pose(problem, X, d, eps, fit_max_error_rel, settings=RepairSettings()):
    """Repair an integrated pose: snap, fallback, snap again, and verify the result.

    Parameters
    ----------
    problem : posefix.verify.state.RepairProblem
    X : (n, 3) float
        Integrated positions.
    d : float
        The reference's bounding-box diagonal (deviations are relative to it).
    eps : float
        The fit's error threshold (length units).
    fit_max_error_rel : float
        The fit's max error at its end, relative to ``d``.
    settings : RepairSettings

    Returns
    -------
    RepairResult
    """
    threshold = settings.fallback_eps * eps  # farther: not reached (pass-through triggers)
    reach = max(threshold, settings.fallback_fit * fit_max_error_rel * d)  # V_C: snap within
    integrated_dev, integrated = deviation(X, problem.V_tgt, problem.mask, d)
    t0 = time.perf_counter()
    X, reproduced = _snap(problem, X, np.zeros(len(X), dtype=np.uint8), reach, settings)
    t1 = time.perf_counter()
    X, replaced, _ = fallback(problem, X, threshold, settings)
    t2 = time.perf_counter()
    X, replaced = _snap(problem, X, replaced, reach, settings)
    replaced |= reproduced
    t3 = time.perf_counter()
    seconds = {"reproduce": (t1 - t0) + (t3 - t2), "fallback": t2 - t1}
    return _verified(problem, X, replaced, (integrated_dev, integrated), d, seconds)


def finish_pose(problem, samples, d, solver, settings=FinishSettings(), frames=None):
    """Repair an integrated pose with the contact finish and verify the result.

    Parameters
    ----------
    problem : posefix.verify.state.RepairProblem
    samples : (S, n, 3) float
        The integrated path lines at their sample times, the integrated pose last.
    d : float
        The reference's bounding-box diagonal (deviations are relative to it).
    solver : posefix.mesh.contact_solver.ContactSolver
        Built on the reference with its intersecting faces tolerated.
    settings : FinishSettings
    frames : (K, n, 3) float, optional
        The key frames (the elastic finish's second candidate start, :func:`contact_finish`).

    Returns
    -------
    RepairResult
        Flags: ``REPRODUCED`` on the constrained vertices exactly on their targets, ``CONTACT`` on the vertices
        a contact holds off their goals, ``REPLACED_NEW_INTERSECTION`` where the target undid the reference's own
        intersections; the metrics add the finish's (:func:`contact_finish`).
    """
    integrated = deviation(samples[-1], problem.V_tgt, problem.mask, d)
    finish = contact_finish(problem, solver, samples, settings, frames)
    replaced = (finish.exact * np.uint8(REPRODUCED) | finish.contact * np.uint8(CONTACT)
                | finish.untangled * np.uint8(REPLACED_NEW_INTERSECTION))
    result = _verified(problem, finish.X, replaced, integrated, d, {"contact": finish.metrics["contact_seconds"]},
                       finish.pairs)
    result.metrics |= {k: v for k, v in finish.metrics.items() if k != "contact_seconds"}
    return result


def finish_settings(options):
    """``(RepairSettings, FinishSettings, ContactSettings)`` from a mapping holding their fields by name: the
    pipeline's config sections ``verify`` and ``contact`` merged, or a stage's parsed options (``vars(args)``)."""
    return tuple(kind(**{f.name: options[f.name] for f in fields(kind)})
                 for kind in (RepairSettings, FinishSettings, ContactSettings))


def finished_pose(problem, paths, d, settings, fit_errors):
    """Repair an integrated pose with the finish of ``settings`` and verify it (:func:`finish_pose` or the snap
    finish's :func:`repair_pose`).

    Parameters
    ----------
    problem : posefix.verify.state.RepairProblem
    paths : tuple
        The integrated path lines at their sample times (S, n, 3), the integrated pose last, and the key frames
        (K, n, 3).
    d : float
        The reference's bounding-box diagonal (length units).
    settings : tuple
        :func:`finish_settings`'s.
    fit_errors : tuple of float
        The fit's error threshold (length units) and its max error at its end relative to ``d`` (the snap
        finish's reach).

    Returns
    -------
    RepairResult
    """
    (samples, frames), (repair, finish, contact) = paths, settings
    if repair.finish == "snap":
        return repair_pose(problem, samples[-1], d, fit_errors[0], fit_errors[1], repair)
    solver = ContactSolver(problem.V_ref, problem.F, problem.frame_pairs[0], contact)
    return finish_pose(problem, samples, d, solver, finish, frames)


def _verified(problem, X, replaced, integrated, d, seconds, pairs=None):
    """The :class:`RepairResult` of a finished pose ``X`` with its flags; ``integrated``: the integrated pose's
    (deviation, summary); ``seconds``: the finish's, ``verify`` added; ``pairs``: ``X``'s intersecting face pairs
    when the finish has them."""
    t0 = time.perf_counter()
    pairs = self_intersecting_pairs(X, problem.F) if pairs is None else pairs
    faces = intersecting_faces(pairs, len(problem.F))
    dev, summary = deviation(X, problem.V_tgt, problem.mask, d)
    seconds = seconds | {"verify": time.perf_counter() - t0}
    result = RepairResult(X, replaced, pairs, faces, faces & ~problem.reference_faces, dev, integrated[0],
                          summary, integrated[1], seconds)
    result.metrics = _metrics(result, problem)
    _log_result(result)
    return result


def _snap(problem, X, replaced, reach, settings):
    """Snap the constrained vertices within ``reach`` of their targets, outside fallback regions."""
    if not settings.reproduce:
        return X, replaced
    reached = np.linalg.norm(X - problem.V_tgt, axis=1) <= reach
    keep = problem.mask & reached & (replaced == 0)
    X, moved, pushed = reproduce_targets(problem, X, keep, (replaced > 0) | (problem.mask & ~reached))
    return X, replaced | (moved * np.uint8(REPRODUCED)) | (pushed * np.uint8(PUSHED))


def _metrics(r, problem):
    """The scalar results of ``verify.h5`` of a :class:`RepairResult`, dict."""
    m = len(problem.F)
    return {"vertices": len(r.X), "faces": m,
            "intersecting_faces_reference": int(problem.reference_faces.sum()),
            "intersecting_faces_target": int(problem.target_faces.sum()),
            "intersecting_faces_repaired": int(r.faces.sum()), "repaired_new": int(r.new.sum()),
            "intersecting_faces_keyframes_max": int(max(intersecting_faces(p, m).sum() for p in problem.frame_pairs)),
            **flag_counts(r.replaced, r.new, problem.F),
            **{f"deviation_{k}": v for k, v in r.summary.items()},
            **{f"integrated_deviation_{k}": v for k, v in r.integrated.items()}}


def _log_result(result):
    m = result.metrics
    log.info("%s", ", ".join(f"{k} {v:.3f} s" for k, v in result.seconds.items()))
    log.info("intersecting faces: reference %d, target %d, repaired %d (new %d); %d vertices changed by the fallback",
             m["intersecting_faces_reference"], m["intersecting_faces_target"], m["intersecting_faces_repaired"],
             m["repaired_new"], m["fallback_vertices"])
    s, i = result.summary, result.integrated
    log.info("deviation / d: constrained mean %.2e max %.2e, free mean %.2e max %.2e (integrated: %.2e, %.2e)",
             s["constrained_mean"], s["constrained_max"], s["free_mean"], s["free_max"],
             i["constrained_mean"], i["constrained_max"])
