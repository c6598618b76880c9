"""The skeletal mesh of a surface (Yoshizawa, Belyaev, Seidel 2007, §2).

Vertex ``i`` of the skeletal mesh ``S`` is the centre ``s_i`` of a medial ball touching the surface
at ``x_i`` (``S`` has the surface's connectivity), with radius ``R_i = |x_i - s_i|``, so that
``x = s + R n`` (the paper's equation (1)). Construction:

1. Medial centres (``medial``): the inner Voronoi poles as in the paper (``"poles"``), the
   shrinking balls of Ma et al. 2012 (``"shrinking_ball"``), or (``"auto"``) the poles with every
   missing or bad pole (:func:`~posefix.medial.quality.bad_centres`) replaced by the shrinking-ball
   centre of its vertex, and where that is bad too, by the largest of the balls ``x - r n`` with
   ``r = R_sb / 2^k`` (k = 0..12) that is inside and does not cross the surface; when none passes,
   the inside one with the largest clearance (or ``R_sb / 2^12`` if none is inside), still flagged bad.
2. The paper's "gentle simplification": ``smooth_iters`` explicit steps of the bi-Laplacian flow
   ``s_t = -L^2 s`` with the uniform (umbrella) Laplacian ``L`` of the surface's connectivity, each
   step applied only at the vertices where the speed has a negative inner product with ``x - s``
   (the flow moves those centres deeper, away from their surface point).
3. ``R = |x - s|``.
"""

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from posefix.mesh.geometry import bbox_diagonal, vertex_normals
from posefix.mesh.laplacian import uniform_laplacian
from posefix.mesh.topology import vertex_adjacency
from posefix.mesh.winding import winding_numbers
from posefix.medial.poles import inner_poles
from posefix.mesh.distance import surface_distance_below
from posefix.medial.quality import bad_centres
from posefix.medial.shrinking_ball import shrinking_ball_centers
from posefix.mesh.tolerances import TINY

log = logging.getLogger(__name__)

NONE, POLE, SHRINKING_BALL, RAY = 0, 1, 2, 3
SOURCES = ("none", "pole", "shrinking_ball", "ray")  # names of the ``source`` codes
MEDIAL = ("poles", "shrinking_ball", "auto")
_HALVINGS = 12


@dataclass(frozen=True)
class SkeletalMesh:
    """A skeletal mesh: the surface's connectivity on medial-ball centres.

    Attributes
    ----------
    S : (n, 3) float
        Ball centres (after smoothing); NaN where no centre was found (``medial="poles"`` only).
    R : (n,) float
        Radii ``|x - s|``, in the units of the surface.
    source : (n,) int8
        Method of each centre: ``NONE``, ``POLE``, ``SHRINKING_BALL`` or ``RAY`` (names in ``SOURCES``).
    bad : (n,) bool
        The centre was bad (outside, crossing or missing) after the fallbacks, before smoothing.
    stats : dict
        Counts (``poles_missing``, ``poles_outside``, ``poles_crossing``, ``replaced_by_ball``,
        ``replaced_by_ray``, ``bad``, ``smoothed``: vertices moved at least once) and ``seconds``.
    """

    S: np.ndarray
    R: np.ndarray
    source: np.ndarray
    bad: np.ndarray
    stats: dict = field(default_factory=dict)


def skeletal_mesh(V, F, medial="auto", smooth_iters=10, smooth_step=0.1, tol=0.5):
    """Build the skeletal mesh of a triangle mesh.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
        Outward-oriented surface; may be open, non-manifold or self-intersecting.
    medial : {"poles", "shrinking_ball", "auto"}
        Medial centres: the paper's Voronoi poles, shrinking balls, or poles with fallbacks.
    smooth_iters : int
        Steps of the gated bi-Laplacian flow (0: none).
    smooth_step : float
        Step of the flow (stable below 0.5 for the umbrella operator).
    tol : float
        Crossing slack of :func:`~posefix.medial.quality.bad_centres`.

    Returns
    -------
    SkeletalMesh
    """
    if medial not in MEDIAL:
        raise ValueError(f"medial must be one of {MEDIAL}, not {medial!r}")
    start = time.perf_counter()
    V = np.asarray(V, dtype=np.float64)
    N = vertex_normals(V, F)
    S, source, bad, stats = _medial_centres(V, F, N, medial, tol)
    S, moved = gated_bilaplacian_flow(S, V, vertex_adjacency(F, len(V)), smooth_iters, smooth_step)
    R = np.linalg.norm(V - S, axis=1)
    stats.update(bad=int(bad.sum()), smoothed=int(moved.sum()), seconds=round(time.perf_counter() - start, 3))
    log.info("skeletal mesh of %d vertices (%s): %s", len(V), medial, stats)
    return SkeletalMesh(S=S, R=R, source=source, bad=bad, stats=stats)


def _medial_centres(V, F, N, medial, tol):
    """Centres (n, 3), source codes (n,) int8, bad mask (n,) and counts of step 1."""
    stats = {}
    if medial == "shrinking_ball":
        S, R, _ = shrinking_ball_centers(V, N, bbox_diagonal(V))
        source = np.full(len(V), SHRINKING_BALL, dtype=np.int8)
        return S, source, bad_centres(V, F, S, R, tol).bad, stats
    S, found = inner_poles(V, N)
    source = np.where(found, POLE, NONE).astype(np.int8)
    quality = bad_centres(V, F, S, np.linalg.norm(V - S, axis=1), tol)
    stats.update(poles_missing=int(quality.nonfinite.sum()), poles_outside=int(quality.outside.sum()),
                 poles_crossing=int(quality.crossing.sum()))
    bad = quality.bad
    if medial == "poles" or not bad.any():
        return S, source, bad, stats
    idx = np.flatnonzero(bad)
    S_ball, R_ball, _ = shrinking_ball_centers(V, N, bbox_diagonal(V))
    S[idx], source[idx] = S_ball[idx], SHRINKING_BALL
    bad[idx] = bad_centres(V, F, S_ball[idx], R_ball[idx], tol).bad
    stats["replaced_by_ball"] = len(idx)
    idx = np.flatnonzero(bad)
    if len(idx):
        S[idx], bad[idx] = ray_centres(V, F, V[idx], N[idx], R_ball[idx], tol)
        source[idx] = RAY
    stats["replaced_by_ray"] = len(idx)
    return S, source, bad, stats


def ray_centres(V, F, X, N, r_max, tol):
    """The largest inner ball tangent at each point, among ``r_max / 2^k``, that is inside and empty.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
        The surface.
    X, N : (k, 3) float
        Surface points and their outward unit normals.
    r_max : (k,) float
        Largest radius tried.
    tol : float
        Crossing slack (as in :func:`~posefix.medial.quality.bad_centres`).

    Returns
    -------
    S : (k, 3) float
        Centres ``X - r N``: the largest passing ``r``; where none passes, the inside candidate with
        the largest clearance (distance to the surface over ``r``), or the smallest ``r`` when none
        is inside.
    bad : (k,) bool
        No candidate passed.
    """
    r = np.asarray(r_max, dtype=np.float64)[:, None] * 0.5 ** np.arange(_HALVINGS + 1)  # (k, K)
    C = (X[:, None, :] - r[..., None] * N[:, None, :]).reshape(-1, 3)
    inside = (winding_numbers(V, F, C) >= 0.5).reshape(r.shape)
    clearance = surface_distance_below(V, F, C, r.ravel()).reshape(r.shape) / np.maximum(r, TINY)
    passing = inside & (clearance >= 1.0 - tol)
    ok = passing.any(axis=1)
    best = np.argmax(np.where(inside, clearance, -1.0), axis=1)  # ties: the larger r
    pick = np.where(ok, np.argmax(passing, axis=1), np.where(inside.any(axis=1), best, _HALVINGS))
    rows = np.arange(len(X))
    return X - r[rows, pick][:, None] * N, ~ok


def gated_bilaplacian_flow(S, X, A, iters, step):
    """The paper's gated bi-Laplacian flow on a skeletal mesh.

    Parameters
    ----------
    S : (n, 3) float
        Skeletal vertices; NaN ones stay NaN and freeze their neighbours (their speed is NaN).
    X : (n, 3) float
        Surface vertices.
    A : (n, n) sparse bool
        Vertex adjacency of the surface.
    iters : int
    step : float
        Explicit Euler step (the umbrella ``L^2`` has eigenvalues in [0, 4]: stable below 0.5).

    Returns
    -------
    S : (n, 3) float
        Smoothed vertices: ``s += step * v`` at each step, with ``v = -L^2 s``, only where
        ``v . (x - s) < 0``.
    moved : (n,) bool
        Vertices moved at least once.
    """
    L = uniform_laplacian(A)
    S = np.array(S, dtype=np.float64)
    moved = np.zeros(len(S), dtype=bool)
    for _ in range(iters):
        speed = -(L @ (L @ S))
        gate = np.einsum("ij,ij->i", speed, X - S) < 0
        S[gate] += step * speed[gate]
        moved |= gate
    return S, moved
