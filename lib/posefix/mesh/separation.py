"""Pushing intersecting triangle pairs apart along a separating axis taken from a clean pose.

Two triangles that share no vertex and do not intersect are separated by a plane whose normal is
one of 11 axes (separating axis theorem): the two face normals and the nine cross products of an
edge of one with an edge of the other. For a pair that intersects in a pose ``Y`` but not in a
clean pose ``Z`` (the integrated pose before a snap, or the reference), :func:`separating_axes`
picks, in ``Z``, the axis with the widest gap and orients it from the first triangle to the second
(rotated into ``Y``'s frame by the pair's best-fit rotation, so that a reference-pose axis is
meaningful in a posed mesh). :func:`separate` then moves the movable vertices of ``Y`` by
cyclic projections onto the linear constraints ``a . (y_j - y_i) >= margin`` (``i`` in the first
triangle, ``j`` in the second): the smallest moves, shared between the two sides in proportion to
their mobilities, that restore the clean pose's order along the axis.
"""

import numpy as np

from posefix.mesh.rotations import kabsch
from posefix.mesh.tolerances import ROUNDOFF, TINY

_EDGES = ((0, 1), (1, 2), (2, 0))


def separating_axes(Z, F, pairs, Y=None):
    """The widest separating axis in ``Z`` of each face pair, oriented from the first face to the second.

    Parameters
    ----------
    Z : (n, 3) float
        Pose in which the pairs do not intersect.
    F : (m, 3) int
    pairs : (k, 2) int
        Face pairs sharing no vertex.
    Y : (n, 3) float, optional
        Pose the axes are used in; each axis is rotated by the rotation that best maps the pair's
        six vertices from ``Z`` to ``Y`` (:func:`posefix.mesh.rotations.kabsch`). Default: ``Z``.

    Returns
    -------
    axes : (k, 3) float
        Unit axes (zero where none separates).
    gaps : (k,) float
        Gap between the two projections along the axis in ``Z`` (length units; <= 0: not separated).
    """
    A, B = Z[F[pairs[:, 0]]], Z[F[pairs[:, 1]]]
    candidates = [_normal(A), _normal(B)]
    for i, j in _EDGES:
        for k, l in _EDGES:
            candidates.append(np.cross(A[:, j] - A[:, i], B[:, l] - B[:, k]))
    C = np.stack(candidates, axis=1)  # (k, 11, 3)
    norm = np.linalg.norm(C, axis=2, keepdims=True)
    C = np.divide(C, norm, out=np.zeros_like(C), where=norm > 1e-300)
    pa, pb = np.einsum("kci,kvi->kcv", C, A), np.einsum("kci,kvi->kcv", C, B)
    forward = pb.min(axis=2) - pa.max(axis=2)  # B after A along +axis
    backward = pa.min(axis=2) - pb.max(axis=2)
    gap = np.maximum(forward, backward)
    gap[norm[..., 0] <= TINY] = -np.inf
    best = np.argmax(gap, axis=1)
    rows = np.arange(len(pairs))
    axes = C[rows, best] * np.where(forward[rows, best] >= backward[rows, best], 1.0, -1.0)[:, None]
    gaps = gap[rows, best]
    if Y is not None:
        for r, (f, g) in enumerate(pairs):
            idx = np.concatenate([F[f], F[g]])
            R, _, _ = kabsch(Z[idx], Y[idx], np.ones(6))
            axes[r] = R @ axes[r]
    axes[~(gaps > 0)] = 0.0
    return axes, gaps


def separate(Y, F, pairs, axes, mobility, margin, sweeps=50):
    """Move vertices so that each pair's first face lies below its second along the pair's axis.

    Parameters
    ----------
    Y : (n, 3) float
        Pose to change.
    F : (m, 3) int
    pairs : (k, 2) int
        Face pairs sharing no vertex.
    axes : (k, 3) float
        Unit axes from :func:`separating_axes` (zero rows are skipped).
    mobility : (n,) float
        How readily each vertex moves (0 = fixed; the correction of a violated constraint is split
        between its two vertices in proportion to their mobilities).
    margin : float or (k,) float
        Required gap along the axis (length units).
    sweeps : int
        Most passes over all constraints.

    Returns
    -------
    X : (n, 3) float
        Changed pose.
    feasible : bool
        Whether every constraint of the pairs with an axis holds at the end.
    """
    X = Y.copy()
    margin = np.broadcast_to(np.asarray(margin, dtype=np.float64), (len(pairs),))
    use = np.flatnonzero(np.linalg.norm(axes, axis=1) > 0)
    i = np.repeat(F[pairs[use, 0]], 3, axis=1).ravel()  # (9 k,) vertex of the first face
    j = np.tile(F[pairs[use, 1]], (1, 3)).ravel()  # vertex of the second face
    a = np.repeat(axes[use], 9, axis=0)
    need = np.repeat(margin[use], 9)
    total = mobility[i] + mobility[j]
    movable = total > 0
    for _ in range(sweeps):
        worst = 0.0
        for c in np.flatnonzero(movable):  # Gauss-Seidel: every projection sees the previous ones
            short = need[c] - a[c] @ (X[j[c]] - X[i[c]])
            if short > 0:
                worst = max(worst, short)
                X[j[c]] += a[c] * short * mobility[j[c]] / total[c]
                X[i[c]] -= a[c] * short * mobility[i[c]] / total[c]
        if worst == 0.0:
            break
    short = need - np.einsum("ki,ki->k", a, X[j] - X[i])
    return X, bool(np.all(short <= ROUNDOFF * (1.0 + need)))


def _normal(T):
    return np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
