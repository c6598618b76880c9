"""The inputs of one pose's repair and the state the repairs change.

*New* intersecting faces are faces that intersect in the repaired pose but not in the reference
(the reference's own intersections are reproduced by design, S0 §4.3).
"""

import logging
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.mesh.topology import vertex_adjacency

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class RepairProblem:
    """The fixed inputs of one pose's repair.

    Attributes
    ----------
    V_ref, V_tgt : (n, 3) float
        Reference and target positions.
    F : (m, 3) int
    mask : (n,) bool
        ``V_C``, the constrained vertices.
    frame_pairs : list of (k_i, 2) int
        Intersecting face pairs per key frame (frame 0 the reference, the last the target).
    A : (n, n) sparse bool
        Vertex adjacency.
    reference_faces, target_faces : (m,) bool
        Faces intersecting in the reference and in the target.
    """

    V_ref: np.ndarray
    V_tgt: np.ndarray
    F: np.ndarray
    mask: np.ndarray
    frame_pairs: list
    A: sp.csr_matrix
    reference_faces: np.ndarray
    target_faces: np.ndarray

    @classmethod
    def build(cls, V_ref, V_tgt, F, mask, frame_pairs):
        """The problem of repairing ``V_tgt`` (arguments as the attributes of the same name)."""
        m = len(F)
        return cls(V_ref, V_tgt, F, mask, frame_pairs, vertex_adjacency(F, len(V_ref)),
                   intersecting_faces(frame_pairs[0], m), intersecting_faces(frame_pairs[-1], m))


class RepairState:
    """Repaired positions with their intersecting pairs, new faces and flags (:mod:`posefix.verify.flags`).

    Parameters
    ----------
    X : (n, 3) float
        Positions (copied).
    F : (m, 3) int
    reference_faces : (m,) bool
        Faces intersecting in the reference (never new).
    """

    def __init__(self, X, F, reference_faces):
        self.X, self.F, self.reference_faces = X.copy(), F, reference_faces
        self.pairs = self_intersecting_pairs(self.X, F)
        self.new = intersecting_faces(self.pairs, len(F)) & ~reference_faces
        self.replaced = np.zeros(len(X), dtype=np.uint8)

    def copy(self):
        """A state that can be changed without changing this one (positions are replaced, not edited)."""
        other = object.__new__(RepairState)
        other.__dict__.update(self.__dict__)
        other.replaced = self.replaced.copy()
        return other

    def trial(self, region, positions):
        """``(X, pairs, new)`` with the vertices ``region`` moved to ``positions[region]``, (n, 3) float."""
        X = self.X.copy()
        X[region] = positions[region]
        pairs = self_intersecting_pairs(X, self.F)
        return X, pairs, intersecting_faces(pairs, len(self.F)) & ~self.reference_faces

    def improves(self, trial):
        """Whether a :meth:`trial` removes new faces and adds none."""
        return not (trial[2] & ~self.new).any() and trial[2].sum() < self.new.sum()

    def accept(self, trial, region, flag):
        """Take a :meth:`trial` and flag the vertices it moved (``region``) with ``flag``."""
        self.X, self.pairs, self.new = trial
        self.replaced[region] |= flag

    def log_trial(self, kind, region, new, ok):
        """Log a fallback tried on ``region`` (vertex indices) that leaves the faces ``new`` (m,) bool."""
        log.info("fallback (%s) on %d vertices: %s (new faces %d -> %d)", kind, len(region),
                 "applied" if ok else "rejected", self.new.sum(), new.sum())
