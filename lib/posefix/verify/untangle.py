"""Untangling new intersections: remedies tried on the regions around the faces that newly intersect.

Exactly moved vertices joined by straight triangles, and the fit's residual error, can push two
nearby surfaces into each other although the continuous flow keeps them apart (thin folds and
near contacts, or the rim of an intersection the reference already has). Both sides of every
such pair, grown by ``ring`` (then ``ring + 1``, ...) rings, get the first of these that removes
new faces and adds none: the pairs' vertices moved apart (less than an edge) along the axis that
separates the two faces in the reference (:mod:`posefix.mesh.separation`); the target's positions;
their unconstrained vertices smoothed (a few Jacobi steps of the uniform Laplacian, boundary
fixed); the reference's shape of the region moved rigidly onto it (least squares), which
restores the reference's own intersection pattern; the whole unconstrained parts the region lies
in copied from the target.
"""

import numpy as np

from posefix.mesh.geometry import edge_lengths
from posefix.mesh.rotations import kabsch
from posefix.mesh.separation import separate, separating_axes
from posefix.mesh.topology import edges, grow_rings, selection_components
from posefix.verify.flags import REPLACED_NEW_INTERSECTION, RIGID_REFERENCE, SEPARATED, SMOOTHED

SMOOTHING_STEPS = (5, 20, 50)
"""Jacobi steps of the smoothing remedy, tried in turn."""
SEPARATION_MARGIN = 0.01
"""Gap left between faces moved apart to untangle a new intersection, in mean edge lengths."""
_REMEDY_NAMES = {SEPARATED: "separation", REPLACED_NEW_INTERSECTION: "target", SMOOTHED: "smoothing",
                 RIGID_REFERENCE: "rigid reference"}


def untangle(problem, state, ring, max_rings):
    """Remedies on regions of ``ring``, ``ring + 1``, ... ``max_rings`` rings until no new face is left.

    Parameters
    ----------
    problem : posefix.verify.state.RepairProblem
    state : posefix.verify.state.RepairState
        Changed in place.
    ring, max_rings : int
    """
    for rings in range(ring, max_rings + 1):
        if not _untangle_round(problem, state, rings):
            break


def _untangle_round(problem, state, rings):
    """One round of the remedies on regions of ``rings`` rings; False if no new face is left."""
    culprit = state.pairs[state.new[state.pairs].any(axis=1)]
    if len(culprit) == 0:
        return False
    F, A = state.F, problem.A
    seeds = np.zeros(len(state.X), dtype=bool)
    seeds[F[culprit].ravel()] = True
    links = np.stack([F[culprit[:, 0], 0], F[culprit[:, 1], 0]], axis=1)
    for region in selection_components(grow_rings(seeds, A, rings), A, links):
        for flag, moved, positions in _remedies(problem, state, region, culprit):
            trial = state.trial(moved, positions)
            ok = state.improves(trial)
            state.log_trial(f"new intersection, {rings} rings, {_REMEDY_NAMES[flag]}", moved, trial[2], ok)
            if ok:
                state.accept(trial, moved, flag)
                break
    return True


def _remedies(problem, state, region, culprit):
    """Candidate fixes of a region, in order: (flag, vertices moved, positions to take them from).

    The first moves only the vertices of the region's intersecting pairs (the smallest change: the
    rim of an intersection the reference has that crept over an edge); the last copies from the
    target the whole unconstrained parts the region lies in (a long unconstrained part such as a
    tail tip can be crumpled beyond any ring of the culprits).
    """
    X, A, mask = state.X, problem.A, problem.mask
    yield from _separation(problem, state, region, culprit)
    yield REPLACED_NEW_INTERSECTION, region, problem.V_tgt
    free = region[~mask[region]]
    for steps in SMOOTHING_STEPS if len(free) else ():
        yield SMOOTHED, free, smooth(X, A, free, steps)
    R, c_ref, c_x = kabsch(problem.V_ref[region], X[region], np.ones(len(region)))
    carried = X.copy()
    carried[region] = (problem.V_ref[region] - c_ref) @ R.T + c_x
    yield RIGID_REFERENCE, region, carried
    if len(free):
        parts = np.zeros(len(mask), dtype=bool)
        for component in selection_components(~mask, A):
            if np.isin(component, free).any():
                parts[component] = True
        parts[region] = True
        yield REPLACED_NEW_INTERSECTION, np.flatnonzero(grow_rings(parts, A, 1)), problem.V_tgt


def _separation(problem, state, region, culprit):
    """The region's pairs moved apart along their separating axis in the reference, when every move
    stays under one mean edge length (at most one remedy)."""
    X, F = state.X, state.F
    inside = np.zeros(len(X), dtype=bool)
    inside[region] = True
    pairs = culprit[inside[F[culprit]].all(axis=(1, 2))]
    if len(pairs):
        edge = edge_lengths(X, edges(F)).mean()
        axes, _ = separating_axes(problem.V_ref, F, pairs, X)
        mobility = np.zeros(len(X))
        mobility[F[pairs].ravel()] = 1.0
        Y, feasible = separate(X, F, pairs, axes, mobility, SEPARATION_MARGIN * edge)
        if feasible and np.linalg.norm(Y - X, axis=1).max() <= edge:
            yield SEPARATED, np.flatnonzero((Y != X).any(axis=1)), Y


def smooth(X, A, region, steps):
    """Jacobi steps ``x <- (x + mean of neighbours) / 2`` on ``region`` only.

    Parameters
    ----------
    X : (n, 3) float
    A : (n, n) sparse bool
        Vertex adjacency.
    region : (k,) int
        Vertices to smooth; the others stay.
    steps : int

    Returns
    -------
    (n, 3) float
    """
    rows = A[region].astype(np.float64)
    deg = np.asarray(rows.sum(axis=1)).ravel()
    Y = X.copy()
    for _ in range(steps):
        Y[region] = 0.5 * Y[region] + 0.5 * (rows @ Y) / deg[:, None]
    return Y
