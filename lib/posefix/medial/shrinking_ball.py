"""The shrinking-ball medial axis (Ma, Bae, Choi, Varshney 2012), all points at once.

For a surface point ``p`` with outward normal ``n``, the inner medial ball touching the surface at
``p`` has its centre on the ray ``c = p - r n``. Starting from a huge ball, each step finds the
sample ``q`` nearest to the current centre and shrinks the ball to the one through ``p`` and ``q``
tangent at ``p``: ``r = |p - q|^2 / (2 n . (p - q))``; it stops when ``r`` no longer changes. The
steps, tolerances and denoising follow the reference implementation ``tudelft3d/masbcpp``
(``compute_ma_processing.cpp``): a ball whose separation angle (between ``p - c`` and ``q - c``)
falls below ``preserve_angle`` after the first step keeps its previous radius (noise would shrink
it further), and one whose first step already has a separation angle below ``planar_angle`` (a
flat, "infinite" ball) keeps ``r_init``. Here every step is one vectorized k-d tree query for all
balls that still shrink.
"""

import logging
import time

import numpy as np
from scipy.spatial import cKDTree

log = logging.getLogger(__name__)


def shrinking_ball_centers(V, N, r_init, preserve_angle=np.radians(20.0), planar_angle=np.radians(32.0),
                           delta=None, max_iter=30):
    """Inner shrinking-ball centre and radius of every point.

    Parameters
    ----------
    V : (n, 3) float
        Surface samples (mesh vertices).
    N : (n, 3) float
        Outward unit normals at ``V``; points with a zero normal get no ball.
    r_init : float
        Initial and largest radius, in the units of ``V`` (e.g. the bounding-box diagonal).
    preserve_angle, planar_angle : float
        Denoising separation angles in radians (masbcpp's defaults, 20 and 32 degrees); 0 disables.
    delta : float, optional
        Convergence tolerance on the radius change; ``1e-6 r_init`` by default.
    max_iter : int
        Shrinking steps at most (masbcpp: 30).

    Returns
    -------
    S (n, 3) float, R (n,) float
        Ball centres ``V - R N`` and radii, at most ``r_init``.
    converged : (n,) bool
        The ball converged (or stopped by the noise rule) to a radius below ``r_init``; False for
        capped ("infinite") balls, balls stopped by ``max_iter`` and points with a zero normal.
    """
    start = time.perf_counter()
    V, N = np.asarray(V, dtype=np.float64), np.asarray(N, dtype=np.float64)
    delta = 1e-6 * r_init if delta is None else delta
    tree, n = cKDTree(V), len(V)
    R, r_prev, converged = np.full(n, float(r_init)), np.zeros(n), np.zeros(n, dtype=bool)
    active = np.flatnonzero(np.linalg.norm(N, axis=1) > 0)
    for step in range(max_iter + 1):
        if len(active) == 0:
            break
        p, nrm = V[active], N[active]
        q, at_p = _nearest_other(tree, V, p - R[active, None] * nrm, p)
        r, stop, capped = _shrink(p, nrm, q, r_prev[active], r_init, step, preserve_angle, planar_angle)
        capped |= at_p & (r_prev[active] == r_init)  # nothing on the inner side: an infinite ball
        r = np.where(capped, r_init, r)
        stop |= capped | (np.abs(r_prev[active] - r) < delta)
        R[active] = r
        converged[active] = stop & ~capped
        r_prev[active] = r
        active = active[~stop]
    S = V - R[:, None] * N
    log.info("shrinking balls of %d points: %d converged in %d steps, %.2f s", n, converged.sum(), step,
             time.perf_counter() - start)
    return S, R, converged


def _nearest_other(tree, V, c, p):
    """The sample nearest to each centre ``c`` that does not coincide with its point ``p``.

    Returns
    -------
    q : (k, 3) float
        NaN rows where the three nearest samples all coincide with ``p``.
    at_p : (k,) bool
        The nearest sample coincides with ``p``.
    """
    _, nn = tree.query(c, k=3)
    cand = V[nn]  # (k, 3, 3)
    other = np.any(cand != p[:, None, :], axis=2)
    q = cand[np.arange(len(c)), np.argmax(other, axis=1)]
    q[~other.any(axis=1)] = np.nan
    return q, ~other[:, 0]


def _shrink(p, n, q, r_prev, r_init, step, preserve_angle, planar_angle):
    """One step of masbcpp's ``sb_point`` for many balls.

    Returns
    -------
    r : (k,) float
        The radius of the ball through ``p`` and ``q``, tangent at ``p``: ``r_init`` when ``q`` is on
        the outer side of the tangent plane (the ball starts over), ``r_prev`` when stopped by noise.
    stop : (k,) bool
        The ball stops (noise, capped, or no ``q``).
    capped : (k,) bool
        It stops at ``r_init``: the radius exceeded it, the first step was planar, or there is no ``q``.
    """
    pq = p - q
    d = np.linalg.norm(pq, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = d * d / (2.0 * np.einsum("ij,ij->i", n, pq))
    capped = (r > r_init) | np.isnan(r)
    r = np.where((r < 0) | ~np.isfinite(r), r_init, np.minimum(r, r_init))
    c = p - r[:, None] * n
    angle = _angle(p - c, q - c)
    keep_prev = (angle < preserve_angle) & (step > 0) & (r > d) & ~capped
    capped |= (angle < planar_angle) & (step == 0)
    r = np.where(keep_prev, r_prev, np.where(capped, r_init, r))
    return r, capped | keep_prev, capped


def _angle(a, b):
    """Angle between paired vectors, (k,) float in radians; NaN vectors give NaN."""
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = np.einsum("ij,ij->i", a, b) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
    return np.arccos(np.clip(cos, -1.0, 1.0))
