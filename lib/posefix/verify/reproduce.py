"""Reproduction of the target on ``V_C``: snap the constrained vertices exactly onto their targets.

The fit reproduces the constrained vertices only up to its error (S0 §6 "Target shape
reproduction"). :func:`reproduce_targets` puts them exactly on their targets and blends the
residual harmonically into the rest. Where a snapped surface would then cut an unconstrained one,
the unconstrained vertices are pushed out along the axis that separated the two faces before the
snap, each push a smooth (biharmonic) bump over a few rings; parts that still intersect go only
as far as they can.
"""

import logging

import numpy as np

from posefix.mesh.geometry import edge_lengths
from posefix.mesh.harmonic import biharmonic_extension, harmonic_extension
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.mesh.separation import separate, separating_axes
from posefix.mesh.topology import edges, grow_rings, selection_components

log = logging.getLogger(__name__)

SEPARATION_ROUNDS = 8
"""Rounds of pushing unconstrained vertices out of contacts a snap adds."""
SEPARATION_MARGIN = 0.05
"""Gap left between a pushed face and its contact, in mean edge lengths."""
SEPARATION_RINGS = 2
"""Rings of unconstrained vertices over which a push fades out (biharmonic bump)."""
HOLD_RINGS = 2
"""Rings around the vertices of faces a snap would make intersect that are held back."""
HOLD_ATTEMPTS = 8
"""Most rounds of holding back more vertices before the snap is abandoned."""
BISECTIONS = 4
"""Bisection steps for the fraction of the correction a held-back part gets."""


def reproduce_targets(problem, X, keep, hold):
    """Move ``keep`` vertices onto their targets and blend the residual harmonically into the rest.

    The correction ``V_tgt - X`` on ``keep`` is extended to the other vertices by the uniform
    Laplacian (:func:`posefix.mesh.harmonic.harmonic_extension`), with zero correction on ``hold``.
    Where the corrected pose has intersecting faces that ``X`` does not (outside the reference's),
    the movable (neither ``keep`` nor ``hold``) vertices of those pairs are pushed out along the
    axis that separated the two faces before the snap (:func:`posefix.mesh.separation.separate`,
    margin :data:`SEPARATION_MARGIN`), each push a biharmonic bump over :data:`SEPARATION_RINGS`
    rings, for at most :data:`SEPARATION_ROUNDS` rounds. For the pairs that still intersect, both
    faces, grown by :data:`HOLD_RINGS` rings, are held back (zero correction) and the blend is
    recomputed, at most :data:`HOLD_ATTEMPTS` times; then ``X`` is returned unchanged. Each
    held-back part then gets the largest fraction of its correction that adds no intersecting
    face, found by :data:`BISECTIONS` bisection steps on [0, 1].

    Parameters
    ----------
    problem : posefix.verify.state.RepairProblem
        Target, faces, adjacency and the reference's intersecting faces.
    X : (n, 3) float
        Current positions.
    keep : (n,) bool
        Vertices to put on their targets (constrained, reached their targets, not in a fallback).
    hold : (n,) bool
        Vertices that must not move (changed by the fallback).

    Returns
    -------
    X : (n, 3) float
    moved : (n,) bool
        Vertices whose position changed.
    pushed : (n,) bool
        Unconstrained vertices pushed out of contacts.
    """
    snap = _Snap(problem, X, keep)
    weight = np.where(keep & ~hold, 1.0, 0.0)
    snap.push_out(weight, hold)
    held = snap.hold_back(weight, hold)
    if held is None:
        log.info("reproduction abandoned after %d attempts", HOLD_ATTEMPTS)
        return X.copy(), np.zeros(len(X), dtype=bool), np.zeros(len(X), dtype=bool)
    Y, weight = snap.settle(*held, weight, hold)
    partly = keep & (weight > 0) & (weight < 1)
    log.info("reproduction: %d constrained vertices put on their targets, %d partly (mean fraction %.2f), "
             "%d held back", np.count_nonzero(keep & (weight == 1.0)), np.count_nonzero(partly),
             weight[partly].mean() if partly.any() else 0.0, np.count_nonzero(keep & (weight == 0)))
    return Y, (Y != X).any(axis=1), snap.pushed


class _Snap:
    """Poses between ``X`` and the target on ``keep``: weighted corrections, blended, plus pushes."""

    def __init__(self, problem, X, keep):
        self.problem, self.X, self.keep = problem, X, keep
        F = problem.F
        self.before = intersecting_faces(self_intersecting_pairs(X, F), len(F)) & ~problem.reference_faces
        self.edge = edge_lengths(X, edges(F)).mean()
        self.push = np.zeros_like(X)  # offsets of unconstrained vertices pushed out of a contact
        self.pushed = np.zeros(len(X), dtype=bool)
        self.conflict = np.zeros(len(X), dtype=bool)

    def blend(self, weight, fixed):
        """Pose with ``weight`` times the correction on ``keep``, plus the pushes, and its intersections.

        Returns ``(Y, pairs, added)``: positions (n, 3), intersecting pairs, and the faces it adds
        (neither the reference's nor ``X``'s).
        """
        p, X, keep = self.problem, self.X, self.keep
        given = np.where(keep[:, None], weight[:, None] * (p.V_tgt - X), 0.0)
        Y = X + harmonic_extension(p.A, given, fixed)
        if self.pushed.any():  # each push a smooth bump over the unconstrained vertices around it
            support = grow_rings(self.pushed, p.A, SEPARATION_RINGS) & ~fixed
            Y += biharmonic_extension(p.A, self.push, self.pushed, support)
        exact = keep & (weight == 1.0)
        Y[exact] = p.V_tgt[exact]  # bitwise, not up to rounding
        pairs = self_intersecting_pairs(Y, p.F)
        return Y, pairs, intersecting_faces(pairs, len(p.F)) & ~p.reference_faces & ~self.before

    def push_out(self, weight, hold):
        """Push the movable vertices out of the contacts the full snap makes (updates the pushes)."""
        F, keep = self.problem.F, self.keep
        mobility = (~keep & ~hold).astype(np.float64)
        contacts = np.zeros((0, 2), dtype=np.int64)
        for _ in range(SEPARATION_ROUNDS):
            Y, pairs, added = self.blend(weight, keep | hold)
            if not added.any():
                break
            contacts = np.unique(np.concatenate([contacts, pairs[added[pairs].any(axis=1)]]), axis=0)
            axes = _contact_axes(self.X, Y, F, contacts, mobility)
            Z, _ = separate(Y, F, contacts, axes, mobility, SEPARATION_MARGIN * self.edge)
            moved = (Z != Y).any(axis=1)
            self.pushed |= moved
            self.push[moved] += Z[moved] - Y[moved]
        if self.pushed.any():
            log.info("reproduction: %d unconstrained vertices pushed out of %d contacts (by up to %.2g mean edge "
                     "lengths)", np.count_nonzero(self.pushed), len(contacts),
                     np.linalg.norm(self.push, axis=1).max() / self.edge)

    def hold_back(self, weight, hold):
        """Hold back (``weight`` 0, in place) the rings around faces the snap still makes intersect.

        Returns the pose that adds no intersection (n, 3) and the held vertices (n,) bool, or None when
        :data:`HOLD_ATTEMPTS` rounds do not suffice.
        """
        F, A = self.problem.F, self.problem.A
        held = hold.copy()
        for attempt in range(HOLD_ATTEMPTS):
            Y, pairs, added = self.blend(weight, self.keep | held)
            if not added.any():
                return Y, held
            self.conflict[F[pairs[added[pairs].any(axis=1)]].ravel()] = True
            held |= grow_rings(self.conflict, A, HOLD_RINGS)
            weight[held] = 0.0
            self.pushed &= ~held
            self.push[held] = 0.0
            log.info("reproduction attempt %d adds %d intersecting faces: %d vertices held back",
                     attempt + 1, added.sum(), np.count_nonzero(held))
        return None

    def settle(self, Y, held, weight, hold):
        """Give every held-back part the largest fraction of its correction that adds no intersection.

        First the whole part, then its vertices away from the conflict, each by bisection on
        [0, 1], starting from the pose ``Y`` of :meth:`hold_back`. Returns the pose (n, 3) and the
        weights (n,).
        """
        A, keep = self.problem.A, self.keep
        near = grow_rings(self.conflict, A, 1)
        for part in selection_components(held & ~hold, A):
            fixed = keep | held
            fixed[part[~keep[part]]] = False  # the part's unconstrained vertices follow harmonically
            for subset in (part, part[~near[part]]):
                found = self._bisect(weight, fixed, subset) if len(subset) else None
                if found is not None:
                    Y, weight = found
            held[part[weight[part] > 0]] = False
        return Y, weight

    def _bisect(self, weight, fixed, subset):
        """Largest fraction in (0, 1) for ``weight[subset]`` (by bisection) that adds no intersection.

        Returns the accepted ``(pose, weight)``, or None when none is.
        """
        low, high, best = 0.0, 1.0, None
        for _ in range(BISECTIONS):
            trial = weight.copy()
            trial[subset] = 0.5 * (low + high)
            Z, _, added = self.blend(trial, fixed)
            if added.any():
                high = trial[subset[0]]
            else:
                low, best = trial[subset[0]], (Z, trial)
        return best


def _contact_axes(X, Y, F, pairs, mobility):
    """Separating axes for contacts added by a snap from ``X`` to ``Y``, (k, 3) float.

    Taken from the pose with the fixed vertices where ``Y`` has them and the movable ones where
    ``X`` has them, when the pair is separated there (the axis the movable side can be pushed
    along); otherwise from ``X``.
    """
    axes, gaps = separating_axes(np.where(mobility[:, None] > 0, X, Y), F, pairs)
    fallback_axes, _ = separating_axes(X, F, pairs)
    axes[gaps <= 0] = fallback_axes[gaps <= 0]
    return axes
