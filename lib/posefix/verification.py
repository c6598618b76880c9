"""Verification of a repaired pose and the fallback to the target where integration cannot help.

*New* intersecting faces are faces that intersect in the repaired pose but not in the reference
(the reference's own intersections are reproduced by design, S0 §4.3).

Fallback (S0 §6, Fig. 9, extended): a region of the repaired pose is replaced by the target's
positions when

* **far**: vertices of ``V_C`` end farther than a threshold from their targets — the symptom of key
  frames passing through each other, which a flow cannot reproduce (S0 Fig. 9); or
* **new intersection**: faces intersect that intersect neither in the reference nor, locally, in the
  target — discretization (straight triangles between exactly moved vertices) and fitting error
  can push two nearby surfaces into each other although the continuous flow keeps them apart.

Each trigger set is grown by ``ring`` rings and split into connected components; a component is
replaced only if that adds no new intersecting face (and, for the second trigger, removes some).
"""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from posefix.intersections import intersecting_faces, self_intersecting_pairs
from posefix.topology import grow_rings, vertex_adjacency

REPLACED_FAR = 1
"""Replaced by the target: a constrained vertex ended far from its target (global intersection)."""
REPLACED_NEW_INTERSECTION = 2
"""Replaced by the target: the region had new intersecting faces that the target does not have."""


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


def fallback(X, V_tgt, F, mask, reference_faces, threshold, ring=1, repair_new=True, log=None):
    """Replace regions of the repaired pose by the target where integration could not do its job.

    Parameters
    ----------
    X : (n, 3) float
        Integrated positions.
    V_tgt : (n, 3) float
        Target positions.
    F : (m, 3) int
    mask : (n,) bool
        ``V_C``.
    reference_faces : (m,) bool
        Faces intersecting in the reference.
    threshold : float
        Distance (length units) beyond which a constrained vertex counts as far from its target.
    ring : int
        Rings grown around the trigger vertices.
    repair_new : bool
        Also try the second trigger (new intersections).

    Returns
    -------
    X : (n, 3) float
        Positions after the replacements.
    replaced : (n,) uint8
        ``REPLACED_*`` flags per vertex.
    new : (m,) bool
        New intersecting faces that remain.
    """
    n = len(X)
    X = X.copy()
    A = vertex_adjacency(F, n)
    replaced = np.zeros(n, dtype=np.uint8)
    pairs = self_intersecting_pairs(X, F)
    new = intersecting_faces(pairs, len(F)) & ~reference_faces
    for flag in (REPLACED_FAR, REPLACED_NEW_INTERSECTION) if repair_new else (REPLACED_FAR,):
        seeds = np.zeros(n, dtype=bool)
        links = np.zeros((0, 2), dtype=np.int64)
        if flag == REPLACED_FAR:
            seeds = np.linalg.norm(X - V_tgt, axis=1) > threshold
        else:  # both faces of every pair with a new face, joined: the two sides are replaced together
            culprit = pairs[new[pairs[:, 0]] | new[pairs[:, 1]]]
            seeds[F[culprit].ravel()] = True
            links = np.stack([F[culprit[:, 0], 0], F[culprit[:, 1], 0]], axis=1)
        for component in _components(grow_rings(seeds, A, ring), A, links):
            trial = X.copy()
            trial[component] = V_tgt[component]
            trial_pairs = self_intersecting_pairs(trial, F)
            trial_new = intersecting_faces(trial_pairs, len(F)) & ~reference_faces
            ok = not (trial_new & ~new).any() and (flag == REPLACED_FAR or trial_new.sum() < new.sum())
            if log is not None:
                log.info("fallback (%s) region of %d vertices: %s (new faces %d -> %d)",
                         "far from target" if flag == REPLACED_FAR else "new intersection", len(component),
                         "replaced by the target" if ok else "kept", new.sum(), trial_new.sum())
            if ok:
                X, pairs, new = trial, trial_pairs, trial_new
                replaced[component] |= flag
    return X, replaced, new


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
