"""How much a deformation stretches or crushes faces: per-face edge-length and area ratios against a rest shape.

A ratio ``r`` and its inverse are equally bad, so every ratio here is ``max(r, 1/r) >= 1``; a face degenerate
in the rest shape and not in the deformed one has ratio ``inf``, degenerate in both: 1.
"""

import numpy as np

from posefix.mesh.geometry import face_areas

DISTORTION_LIMIT = 4.0
"""Ratio beyond which a face counts as distorted by default (config ``summary.distortion_limit``: a pose's status)."""
SEVERE = 10.0
"""Ratio beyond which a face is severely distorted (:func:`distortion_summary`'s ``faces_severe``)."""
DISTORTED_SHARE = 1e-3
"""Share of a mesh's faces beyond a distortion limit above which its shape needs a look (a pose's status; one
crushed face of 10,000 is noise)."""


def _symmetric_ratio(a, b):
    """``max(a/b, b/a)`` elementwise for non-negative ``a``, ``b``: 1 where both are 0, inf where one is."""
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.maximum(a / b, b / a)
    return np.where((a == 0) & (b == 0), 1.0, r)


def face_distortion(X, V, F):
    """Per-face worst edge-length ratio and area ratio of ``X`` against ``V``.

    Parameters
    ----------
    X, V : (n, 3) float
        Deformed and rest positions.
    F : (m, 3) int

    Returns
    -------
    edge : (m,) float
        ``max(r, 1/r)`` of the face's three edge-length ratios, the worst, >= 1.
    area : (m,) float
        ``max(r, 1/r)`` of the face's area ratio, >= 1.

    Examples
    --------
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]); F = np.array([[0, 1, 2]])
    >>> edge, area = face_distortion(V * [2.0, 1.0, 1.0], V, F)
    >>> float(edge[0]), float(area[0])
    (2.0, 2.0)
    """
    lengths = [np.linalg.norm(P[F[:, [1, 2, 0]]] - P[F], axis=2) for P in (X, V)]
    edge = _symmetric_ratio(*lengths).max(axis=1)
    return edge, _symmetric_ratio(face_areas(X, F), face_areas(V, F))


def distorted_faces(X, rests, F, limit):
    """Faces of ``X`` whose edge-length or area ratio exceeds ``limit`` against every one of ``rests``.

    Parameters
    ----------
    X : (n, 3) float
    rests : sequence of (n, 3) float
        Rest shapes (e.g. the target and the reference: a face is distorted when it is against both).
    F : (m, 3) int
    limit : float
        Largest tolerated ratio, > 1.

    Returns
    -------
    (m,) bool
    """
    over = np.ones(len(F), dtype=bool)
    for V in rests:
        edge, area = face_distortion(X, V, F)
        over &= (edge > limit) | (area > limit)
    return over


def distortion_summary(X, rests, F, limit=DISTORTION_LIMIT, severe=SEVERE):
    """Worst ratios of ``X`` against each rest shape and the faces over ``limit`` against all of them.

    Parameters
    ----------
    X : (n, 3) float
    rests : dict of str -> (n, 3) float
        Named rest shapes (``target``, ``reference``).
    F : (m, 3) int
    limit : float
        Largest tolerated ratio (pipeline: config ``summary.distortion_limit``).
    severe : float
        Ratio of a severe distortion.

    Returns
    -------
    dict
        ``edge_<name>`` and ``area_<name>``: the worst ratio against each; ``edge_nearest``: the worst over the
        faces of the edge ratio against the rest shape nearer to the face (a face the target crushes and the
        repair keeps near the reference is not stretched); ``faces_over`` and ``faces_severe``: faces beyond
        ``limit`` and beyond ``severe`` against every rest shape (:func:`distorted_faces`); ``limit``.

    Examples
    --------
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]); F = np.array([[0, 1, 2]])
    >>> s = distortion_summary(V * [5.0, 1, 1], {"target": V * [6.0, 1, 1], "reference": V}, F)
    >>> round(s["edge_target"], 3), s["edge_reference"], round(s["edge_nearest"], 3)
    (1.2, 5.0, 1.2)
    """
    out, nearest = {}, np.full(len(F), np.inf)
    for name, V in rests.items():
        edge, area = face_distortion(X, V, F)
        out[f"edge_{name}"], out[f"area_{name}"] = float(edge.max(initial=1.0)), float(area.max(initial=1.0))
        nearest = np.minimum(nearest, edge)
    out["edge_nearest"] = float(nearest.max(initial=1.0))
    out["faces_over"] = int(distorted_faces(X, list(rests.values()), F, limit).sum())
    out["faces_severe"] = int(distorted_faces(X, list(rests.values()), F, severe).sum())
    return out | {"limit": float(limit)}
