"""Verification of a repaired pose and the fallback to the target where integration cannot help.

*New* intersecting faces are faces that intersect in the repaired pose but not in the reference
(the reference's own intersections are reproduced by design, S0 §4.3).

Two fallbacks replace regions of the repaired pose by the target's positions:

* **pass-through** (S0 §6, Fig. 9): where key frames pass through each other, a flow cannot
  follow: it keeps the parts on their sides, and vertices end far (``threshold``) from their
  targets (see :func:`_pass_through_regions` for the two triggers). Such regions, with the
  unconstrained parts they touch, are replaced by the target when that adds no intersecting face
  the target does not have there (no seam between copied and integrated parts). The target's own
  intersections in the copied region come back with it, as in S0; they are reported separately.
* **new intersection**: faces that still intersect in the repaired pose but not in the reference.
  Exactly moved vertices joined by straight triangles, and the fit's residual error, can push two
  nearby surfaces into each other although the continuous flow keeps them apart (thin folds and
  near contacts, or the rim of an intersection the reference already has). Both sides of every
  such pair, grown by ``ring`` (then ``ring + 1``, ...) rings, get the first of these that removes
  new faces and adds none: the pairs' vertices moved apart (less than an edge) along the axis that
  separates the two faces in the reference (:mod:`posefix.separation`); the target's positions;
  their unconstrained vertices smoothed (a few Jacobi steps of the uniform Laplacian, boundary
  fixed); the reference's shape of the region moved rigidly onto it (least squares), which
  restores the reference's own intersection pattern.

:func:`reproduce_targets` puts constrained vertices exactly on their targets (the fit reproduces
them only up to its error, S0 §6 "Target shape reproduction") and blends the residual harmonically
into the rest. Where a snapped surface would then cut an unconstrained one, the unconstrained
vertices are pushed out along the axis that separated the two faces before the snap, each push a
smooth (biharmonic) bump over a few rings; parts that still intersect go only as far as they
can. Stage ``verify`` runs it before the two fallbacks (constrained vertices it could not snap and that stay
far from their targets are the pass-through triggers) and once more after them.
"""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from posefix.classification import new_pairs
from posefix.geometry import edge_lengths
from posefix.harmonic import biharmonic_extension, harmonic_extension
from posefix.intersections import intersecting_faces, self_intersecting_pairs
from posefix.rotations import kabsch
from posefix.separation import separate, separating_axes
from posefix.topology import edges, grow_rings, vertex_adjacency

REPLACED_PASS_THROUGH = 1
"""Replaced by the target: key frames pass through each other there and integration did not reach the target."""
REPLACED_NEW_INTERSECTION = 2
"""Replaced by the target: the region had new intersecting faces that the target does not have."""
SMOOTHED = 4
"""Unconstrained vertex smoothed to untangle new intersecting faces."""
RIGID_REFERENCE = 8
"""Region replaced by the reference's shape moved rigidly onto it, to untangle new intersecting faces."""
REPRODUCED = 16
"""Moved onto the target (constrained) or by the harmonic blend of the constrained residual (free)."""
PUSHED = 32
"""Unconstrained vertex pushed out of a contact that putting the constrained vertices on their targets makes."""
SEPARATED = 64
"""Moved apart from a face it newly intersects, along the axis that separates the two in the reference."""
SMOOTHING_STEPS = (5, 20, 50)


def deviation(X, V_tgt, mask, d):
    """Per-vertex deviation from the target relative to ``d`` and its summary over ``V_C`` and the rest.

    Returns
    -------
    dev : (n,) float
    summary : dict
        ``constrained_{max,mean,p95}`` and ``free_{max,mean,p95}`` (0 for an empty set).
    """
    dev = np.linalg.norm(X - V_tgt, axis=1) / d
    summary = {}
    for name, sel in (("constrained", mask), ("free", ~mask)):
        part = dev[sel]
        summary[f"{name}_max"] = float(part.max()) if len(part) else 0.0
        summary[f"{name}_mean"] = float(part.mean()) if len(part) else 0.0
        summary[f"{name}_p95"] = float(np.percentile(part, 95)) if len(part) else 0.0
    return dev, summary


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


class _State:
    """Repaired positions with their intersecting pairs, new faces and fallback flags."""

    def __init__(self, X, F, reference_faces):
        self.X, self.F, self.reference_faces = X.copy(), F, reference_faces
        self.pairs = self_intersecting_pairs(self.X, F)
        self.new = intersecting_faces(self.pairs, len(F)) & ~reference_faces
        self.replaced = np.zeros(len(X), dtype=np.uint8)

    def copy(self):
        other = object.__new__(_State)
        other.__dict__.update(self.__dict__)
        other.replaced = self.replaced.copy()
        return other

    def trial(self, region, positions):
        """Positions, pairs and new faces with ``region`` moved to ``positions[region]``."""
        X = self.X.copy()
        X[region] = positions[region]
        pairs = self_intersecting_pairs(X, self.F)
        return X, pairs, intersecting_faces(pairs, len(self.F)) & ~self.reference_faces

    def improves(self, trial):
        """Whether a trial removes new faces and adds none."""
        return not (trial[2] & ~self.new).any() and trial[2].sum() < self.new.sum()

    def accept(self, trial, region, flag):
        self.X, self.pairs, self.new = trial
        self.replaced[region] |= flag


def fallback(X, V_ref, V_tgt, F, mask, frame_pairs, threshold, ring=1, max_rings=3, repair_new=True, log=None):
    """Replace regions of the repaired pose by the target where integration could not do its job.

    Parameters
    ----------
    X : (n, 3) float
        Integrated positions.
    V_ref, V_tgt : (n, 3) float
        Reference and target positions.
    F : (m, 3) int
    mask : (n,) bool
        ``V_C``.
    frame_pairs : list of (k_i, 2) int
        Intersecting face pairs per key frame (frame 0 the reference, the last the target).
    threshold : float
        Distance (length units) beyond which a vertex counts as not having reached its target.
    ring : int
        Rings grown around the trigger vertices (first attempt).
    max_rings : int
        Largest number of rings tried around new intersections.
    repair_new : bool
        Try the new-intersection fallback.

    Returns
    -------
    X : (n, 3) float
        Positions after the replacements.
    replaced : (n,) uint8
        ``REPLACED_*``, ``SMOOTHED`` and ``RIGID_REFERENCE`` flags per vertex.
    new : (m,) bool
        New intersecting faces that remain.
    """
    n, m = len(X), len(F)
    A = vertex_adjacency(F, n)
    target_faces = intersecting_faces(frame_pairs[-1], m)
    state = _State(X, F, intersecting_faces(frame_pairs[0], m))

    def cleanup(state):
        if repair_new:
            _untangle_rounds(state, V_ref, V_tgt, A, mask, ring, max_rings, log)

    far = np.linalg.norm(X - V_tgt, axis=1) > threshold
    for region in _pass_through_regions(F, mask, A, far, ring, frame_pairs):
        trial = state.copy()
        trial.accept(trial.trial(region, V_tgt), region, REPLACED_PASS_THROUGH)
        cleanup(trial)
        seams = trial.new & ~target_faces & ~state.new  # intersections neither before nor in the target
        _log(log, "pass-through, target", region, state, (None, None, trial.new), not seams.any())
        if not seams.any():
            state = trial
    cleanup(state)
    return state.X, state.replaced, state.new


def _untangle_rounds(state, V_ref, V_tgt, A, mask, ring, max_rings, log):
    """Remedies on regions of ``ring``, ``ring + 1``, ... ``max_rings`` rings until no new face is left."""
    for rings in range(ring, max_rings + 1):
        if not _untangle(state, V_ref, V_tgt, A, mask, rings, log):
            break


def _untangle(state, V_ref, V_tgt, A, mask, rings, log):
    """One round of the new-intersection remedies on regions of ``rings`` rings; False if none is left."""
    culprit = state.pairs[state.new[state.pairs].any(axis=1)]
    if len(culprit) == 0:
        return False
    F = state.F
    seeds = np.zeros(len(state.X), dtype=bool)
    seeds[F[culprit].ravel()] = True
    links = np.stack([F[culprit[:, 0], 0], F[culprit[:, 1], 0]], axis=1)
    for region in _components(grow_rings(seeds, A, rings), A, links):
        for flag, moved, positions in _remedies(state, V_tgt, V_ref, A, mask, region, culprit):
            trial = state.trial(moved, positions)
            ok = state.improves(trial)
            _log(log, f"new intersection, {rings} rings, {_REMEDY_NAMES[flag]}", moved, state, trial, ok)
            if ok:
                state.accept(trial, moved, flag)
                break
    return True


_REMEDY_NAMES = {SEPARATED: "separation", REPLACED_NEW_INTERSECTION: "target", SMOOTHED: "smoothing",
                 RIGID_REFERENCE: "rigid reference"}


def _remedies(state, V_tgt, V_ref, A, mask, region, culprit):
    """Candidate fixes of a region, in order: (flag, vertices moved, positions to take them from).

    The first moves only the vertices of the region's intersecting pairs, apart along the axis
    that separates them in the reference (the smallest change: the rim of an intersection the
    reference has that crept over an edge); the last copies from the target the whole
    unconstrained parts the region lies in (a long unconstrained part such as a tail tip can be
    crumpled beyond any ring of the culprits).
    """
    X, F = state.X, state.F
    inside = np.zeros(len(X), dtype=bool)
    inside[region] = True
    pairs = culprit[inside[F[culprit]].all(axis=(1, 2))]
    if len(pairs):
        edge = edge_lengths(X, edges(F)).mean()
        axes, _ = separating_axes(V_ref, F, pairs, X)
        mobility = np.zeros(len(X))
        mobility[F[pairs].ravel()] = 1.0
        Y, feasible = separate(X, F, pairs, axes, mobility, SEPARATION_MARGIN_UNTANGLE * edge)
        if feasible and np.linalg.norm(Y - X, axis=1).max() <= edge:
            yield SEPARATED, np.flatnonzero((Y != X).any(axis=1)), Y
    yield REPLACED_NEW_INTERSECTION, region, V_tgt
    free = region[~mask[region]]
    for steps in SMOOTHING_STEPS if len(free) else ():
        yield SMOOTHED, free, smooth(X, A, free, steps)
    R, c_ref, c_x = kabsch(V_ref[region], X[region], np.ones(len(region)))
    carried = X.copy()
    carried[region] = (V_ref[region] - c_ref) @ R.T + c_x
    yield RIGID_REFERENCE, region, carried
    if len(free):
        parts = np.zeros(len(mask), dtype=bool)
        for component in _components(~mask, A):
            if np.isin(component, free).any():
                parts[component] = True
        parts[region] = True
        yield REPLACED_NEW_INTERSECTION, np.flatnonzero(grow_rings(parts, A, 1)), V_tgt


SEPARATION_ROUNDS = 8
"""Rounds of pushing unconstrained vertices out of contacts a snap adds (:func:`reproduce_targets`)."""
SEPARATION_MARGIN = 0.05
"""Gap left between a pushed face and its contact, in mean edge lengths."""
SEPARATION_MARGIN_UNTANGLE = 0.01
"""Gap left between faces moved apart to untangle a new intersection, in mean edge lengths."""
SEPARATION_RINGS = 2
"""Rings of unconstrained vertices over which a push fades out (biharmonic bump)."""
BISECTIONS = 4
"""Bisection steps for the fraction of the correction a held-back part gets (:func:`reproduce_targets`)."""


def reproduce_targets(X, V_tgt, F, A, keep, hold, reference_faces, rings=2, attempts=8, log=None):
    """Move ``keep`` vertices onto their targets and blend the residual harmonically into the rest.

    The correction ``V_tgt - X`` on ``keep`` is extended to the other vertices by the uniform
    Laplacian (:func:`posefix.harmonic.harmonic_extension`), with zero correction on ``hold``.
    Where the corrected pose has intersecting faces that ``X`` does not (outside
    ``reference_faces``), the movable (neither ``keep`` nor ``hold``) vertices of those pairs are
    pushed out along the axis that separated the two faces before the snap
    (:func:`posefix.separation.separate`, margin :data:`SEPARATION_MARGIN`), each push a
    biharmonic bump over :data:`SEPARATION_RINGS` rings, for at most :data:`SEPARATION_ROUNDS`
    rounds. For the pairs that still intersect, both faces, grown by ``rings`` rings, are held back
    (zero correction) and the blend is recomputed, at most ``attempts`` times; then ``X`` is
    returned unchanged. Each held-back part then gets the largest fraction of its correction
    that adds no intersecting face, found by :data:`BISECTIONS` bisection steps on [0, 1].

    Parameters
    ----------
    X, V_tgt : (n, 3) float
        Current and target positions.
    F : (m, 3) int
    A : (n, n) sparse bool
        Vertex adjacency.
    keep : (n,) bool
        Vertices to put on their targets (constrained, reached their targets, not in a fallback).
    hold : (n,) bool
        Vertices that must not move (changed by the fallback).
    reference_faces : (m,) bool
        Faces intersecting in the reference (not counted as added).

    Returns
    -------
    X : (n, 3) float
    moved : (n,) bool
        Vertices whose position changed.
    pushed : (n,) bool
        Unconstrained vertices pushed out of contacts (:mod:`posefix.separation`).
    """
    before = intersecting_faces(self_intersecting_pairs(X, F), len(F)) & ~reference_faces
    edge = edge_lengths(X, edges(F)).mean()
    push = np.zeros_like(X)  # offsets of unconstrained vertices pushed out of a contact
    pushed = np.zeros(len(X), dtype=bool)

    def blend(weight, fixed):
        """Pose with ``weight`` times the correction on ``keep``, plus the pushes, and the faces it adds."""
        given = np.where(keep[:, None], weight[:, None] * (V_tgt - X), 0.0)
        Y = X + harmonic_extension(A, given, fixed)
        if pushed.any():  # each push a smooth bump over the unconstrained vertices around it
            Y += biharmonic_extension(A, push, pushed, grow_rings(pushed, A, SEPARATION_RINGS) & ~fixed)
        exact = keep & (weight == 1.0)
        Y[exact] = V_tgt[exact]  # bitwise, not up to rounding
        pairs = self_intersecting_pairs(Y, F)
        return Y, pairs, intersecting_faces(pairs, len(F)) & ~reference_faces & ~before

    weight = np.where(keep & ~hold, 1.0, 0.0)
    mobility = (~keep & ~hold).astype(np.float64)
    contacts = np.zeros((0, 2), dtype=np.int64)
    for _ in range(SEPARATION_ROUNDS):
        Y, pairs, added = blend(weight, keep | hold)
        if not added.any():
            break
        contacts = np.unique(np.concatenate([contacts, pairs[added[pairs].any(axis=1)]]), axis=0)
        Z, _ = separate(Y, F, contacts, _contact_axes(X, Y, F, contacts, mobility), mobility,
                        SEPARATION_MARGIN * edge)
        moved = (Z != Y).any(axis=1)
        pushed |= moved
        push[moved] += Z[moved] - Y[moved]
    if pushed.any():
        _log_info(log, "reproduction: %d unconstrained vertices pushed out of %d contacts (by up to %.2g mean edge "
                  "lengths)", np.count_nonzero(pushed), len(contacts),
                  np.linalg.norm(push, axis=1).max() / edge)
    held, conflict = hold.copy(), np.zeros(len(X), dtype=bool)
    for attempt in range(attempts):
        Y, pairs, added = blend(weight, keep | held)
        if not added.any():
            break
        conflict[F[pairs[added[pairs].any(axis=1)]].ravel()] = True
        held |= grow_rings(conflict, A, rings)
        weight[held] = 0.0
        pushed &= ~held
        push[held] = 0.0
        _log_info(log, "reproduction attempt %d adds %d intersecting faces: %d vertices held back",
                  attempt + 1, added.sum(), np.count_nonzero(held))
    else:
        _log_info(log, "reproduction abandoned after %d attempts", attempts)
        return X.copy(), np.zeros(len(X), dtype=bool), np.zeros(len(X), dtype=bool)
    near = grow_rings(conflict, A, 1)
    for part in _components(held & ~hold, A):
        fixed = keep | held
        fixed[part[~keep[part]]] = False  # the part's unconstrained vertices follow harmonically
        outer = part[~near[part]]  # first the whole part, then the part away from the conflict further
        for subset, low in ((part, 0.0), (outer, weight[part[0]])):
            found = _bisect(blend, weight, fixed, subset, low) if len(subset) else None
            if found is not None:
                Y, weight = found
        held[part[weight[part] > 0]] = False
    partly = keep & (weight > 0) & (weight < 1)
    _log_info(log, "reproduction: %d constrained vertices put on their targets, %d partly (mean fraction %.2f), "
              "%d held back", np.count_nonzero(keep & (weight == 1.0)), np.count_nonzero(partly),
              weight[partly].mean() if partly.any() else 0.0, np.count_nonzero(keep & (weight == 0)))
    return Y, (Y != X).any(axis=1), pushed


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


def _bisect(blend, weight, fixed, subset, low):
    """Largest fraction in (low, 1) for ``weight[subset]`` (by bisection) that ``blend`` accepts.

    Returns the accepted ``(pose, weight)``, or None when none above ``low`` is.
    """
    high, best = 1.0, None
    for _ in range(BISECTIONS):
        trial = weight.copy()
        trial[subset] = 0.5 * (low + high)
        Z, _, added = blend(trial, fixed)
        if added.any():
            high = trial[subset[0]]
        else:
            low, best = trial[subset[0]], (Z, trial)
    return best


def smooth(X, A, region, steps):
    """Jacobi steps ``x <- (x + mean of neighbours) / 2`` on ``region`` only, (n, 3) float."""
    rows = A[region].astype(np.float64)
    deg = np.asarray(rows.sum(axis=1)).ravel()
    Y = X.copy()
    for _ in range(steps):
        Y[region] = 0.5 * Y[region] + 0.5 * (rows @ Y) / deg[:, None]
    return Y


def _pass_through_regions(F, mask, A, far, ring, frame_pairs):
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
    """
    target_pairs = frame_pairs[-1]
    target_faces = intersecting_faces(target_pairs, len(F))
    free = _components(~mask, A)
    seeds = grow_rings(mask & far, A, ring)
    transient = transient_pairs(frame_pairs)
    in_transient = np.zeros(len(mask), dtype=bool)
    in_transient[F[transient].ravel()] = True
    for component in free:
        inside = np.zeros(len(mask), dtype=bool)
        inside[component] = True
        clean = not target_faces[inside[F].any(axis=1)].any()
        if clean and in_transient[component].any() and far[component].any():
            seeds[component] = True
    if not seeds.any():
        return []
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
            break
        region = grown
    return _components(region, A, np.stack([F[target_pairs[:, 0], 0], F[target_pairs[:, 1], 0]], axis=1))


def _log_info(log, *args):
    if log is not None:
        log.info(*args)


def _log(log, kind, region, state, trial, ok):
    if log is not None:
        log.info("fallback (%s) on %d vertices: %s (new faces %d -> %d)", kind, len(region),
                 "applied" if ok else "rejected", state.new.sum(), trial[2].sum())


def _components(selected, A, links=None):
    """Connected components (vertex index arrays, ordered by their smallest vertex) of a selection,
    through mesh edges and the extra vertex ``links`` (k, 2)."""
    idx = np.flatnonzero(selected)
    if len(idx) == 0:
        return []
    graph = A[idx][:, idx].tocoo()
    if links is not None and len(links):
        pos = np.full(len(selected), -1)
        pos[idx] = np.arange(len(idx))
        a, b = pos[links[:, 0]], pos[links[:, 1]]
        ok = (a >= 0) & (b >= 0)
        graph = sp.coo_matrix((np.ones(graph.nnz + ok.sum()), (np.concatenate([graph.row, a[ok]]),
                                                                 np.concatenate([graph.col, b[ok]]))),
                              shape=graph.shape)
    count, labels = connected_components(graph, directed=False)
    return [idx[labels == c] for c in range(count)]
