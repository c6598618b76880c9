"""The contact repair of one pose: the reference carried through the key frames by the contact solver.

Every key frame is a waypoint (:meth:`posefix.mesh.contact_solver.ContactSolver.compute_path`): the solver
starts from the reference, which is intersection-free up to its own intersecting faces (tolerated), and each
Newton step is bounded by CCD, so no new intersection can form on the way; contacts the key frames would
pass through stay open at ``dhat``. The result is the closest such shape to the target that the path reaches.
"""

import logging
from dataclasses import dataclass

import numpy as np

from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs

log = logging.getLogger(__name__)


@dataclass
class TrackingResult:
    """A pose repaired by :func:`track_keyframes`.

    Attributes
    ----------
    X : (n, 3) float
        The repaired pose.
    faces, new_faces : (m,) bool
        Its intersecting faces, and those of them that do not intersect in the reference (the exact detector).
    contact : (n,) bool
        Vertices the barrier holds off the target (closer than ``dhat`` to a part they do not touch at rest).
    metrics : dict
        ``iterations`` (Newton, all key frames), ``converged``, ``contact_vertices``, ``seconds``.
    """

    X: np.ndarray
    faces: np.ndarray
    new_faces: np.ndarray
    contact: np.ndarray
    metrics: dict


def track_keyframes(solver, frames, reference_faces):
    """Carry the reference (``frames[0]``) through the key frames to the target (``frames[-1]``).

    Parameters
    ----------
    solver : posefix.mesh.contact_solver.ContactSolver
        Built on the reference with ``reference_faces`` tolerated.
    frames : (K, n, 3) float
        Key frames, K >= 2: the reference first, the target last.
    reference_faces : (m,) bool
        Faces intersecting in the reference.

    Returns
    -------
    TrackingResult
    """
    result = solver.compute_path(frames[0], frames[1:])
    result.X, _ = solver.keep_gap(result.X, np.ones(len(result.X), dtype=bool))  # survives rounding to float32
    faces = intersecting_faces(self_intersecting_pairs(result.X, solver.F), len(solver.F))
    new = faces & ~reference_faces
    log.info("contact repair: %d key frames tracked in %d Newton iterations (%s), %d vertices in contact, %d new "
             "intersecting faces, %.1f s", len(frames) - 1, result.iterations,
             "converged" if result.converged else "not converged", result.contact.sum(), new.sum(), result.seconds)
    metrics = {"iterations": result.iterations, "converged": bool(result.converged),
               "contact_vertices": int(result.contact.sum()), "seconds": result.seconds}
    return TrackingResult(result.X, faces, new, result.contact, metrics)
