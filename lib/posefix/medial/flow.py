"""The medial-ball flow: evolve a mesh towards the boundary of a union of balls (S1 §4, Eq. 6-10).

The union of the balls ``(s_j^d, R_j)`` is ``f(z) = min_j |z - s_j^d| - R_j`` (Eq. 6). The flow is the
semi-implicit step ``x <- x + tau (I + L)^-1 F(x)`` (Eq. 9: the operator of Eq. 4 with the skeletal vertices
as fixed anchors, prefactorized by :class:`~posefix.medial.reconstruction.SkeletalReconstruction`), with
``F = -f grad f`` (the antigradient of f^2 / 2) from the nearest ball of Eq. 10: for vertex ``i`` the ball
``p`` minimising ``|x_i - s_p^d| - R_p`` over the vertices ``p`` within ``R_i`` of ``x_i`` (a kd-tree of the
moving vertices, rebuilt every iteration). (Eq. 10 as printed drops the sign and the normalisation of
``grad f``; we use the antigradient itself.) A ball that already contained a vertex in the rest pose (its
rest clearance ``c = |x_i - s_j| - R_j < 0``: the skeletal smoothing of S1 §2 and imperfect poles make some
balls overlap neighbouring vertices) counts with that penetration subtracted, so that the rest pose is a
fixed point of the flow; with empty balls (``c >= 0``) this is S1's flow exactly.

Beyond S1, ``margin``: where two parts of the surface interpenetrate, S1's flow pushes both to the ridge
of ``f`` between them, where they end up touching. With a margin, a ball ``j`` whose rest clearance
``c`` from vertex ``i`` exceeds ``margin`` is *foreign* to ``i``: it pushes ``i`` out of
itself inflated by ``min(margin, c - margin)`` (at rest every vertex is at least ``margin`` outside every
inflated foreign ball), in a second term of the speed beside S1's nearest non-foreign ball, so the parts
stop apart and slide along their own balls out of the other part. ``margin = 0`` is S1's flow.
"""

import logging
import time
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.mesh.tolerances import TINY

log = logging.getLogger(__name__)


def union_of_balls(P, centres, radii, chunk=2048):
    """The union-of-balls function ``f(z) = min_j |z - c_j| - r_j`` (Eq. 6), exactly.

    Parameters
    ----------
    P : (k, 3) float
    centres : (n, 3) float
    radii : (n,) float

    Returns
    -------
    (k,) float
        Negative inside the union, zero on its boundary (model units).
    """
    out = np.empty(len(P))
    for a in range(0, len(P), chunk):
        d = np.linalg.norm(P[a:a + chunk, None, :] - centres[None], axis=2) - radii[None]
        out[a:a + chunk] = d.min(axis=1)
    return out


def candidate_balls(X, R, neighbours=64):
    """Eq. 10's candidates: for every vertex ``i`` the vertices ``j`` with ``|x_j - x_i| <= R_i``.

    Parameters
    ----------
    X : (n, 3) float
    R : (n,) float
    neighbours : int
        Keep only the nearest this many of them: bounded work and memory where balls hold many vertices
        (their number grows with the square of the resolution); 0: all of them (S1).

    Returns
    -------
    j : (k,) int64
        Candidates, grouped by vertex in vertex order (each vertex is its own candidate).
    counts : (n,) int64
        Candidates per vertex (at least 1).
    """
    tree = cKDTree(X)
    if not neighbours:
        lists = tree.query_ball_point(X, R, return_sorted=False)
        counts = np.fromiter(map(len, lists), dtype=np.int64, count=len(X))
        return np.concatenate(lists).astype(np.int64), counts
    distance, j = tree.query(X, k=min(neighbours, len(X)), distance_upper_bound=float(R.max()))
    keep = distance.reshape(len(X), -1) <= R[:, None]
    return j.reshape(len(X), -1)[keep].astype(np.int64), keep.sum(axis=1)


def nearest_balls(X, S_d, R, clearance, margin=0.0, neighbours=64):
    """The balls of Eq. 10 for every vertex: the nearest one, and with a margin the nearest foreign one.

    Parameters
    ----------
    X : (n, 3) float
        Current mesh vertices.
    S_d : (n, 3) float
        Ball centres (the deformed skeletal mesh); ``R`` (n,) their radii.
    clearance : callable
        ``clearance(i, j)`` -> rest clearances (k,) of vertices ``i`` from balls ``j`` (model units).
    margin : float
        Balls clearer than this of the vertex at rest are *foreign*, inflated by ``min(margin, c - margin)``
        (model units).
    neighbours : int
        Candidates per vertex at most (:func:`candidate_balls`; 0: all).

    Returns
    -------
    near : tuple of (n,) float, (n,) int
        ``|x_i - s_p| - R_p - min(c, 0)`` and ``p`` for the nearest non-foreign ball (all balls when
        ``margin = 0``: S1's approximation of ``f(x_i)``).
    foreign : tuple of (n,) float, (n,) int
        The same for the nearest foreign ball, inflated; value ``inf`` where there is none.
    """
    j, counts = candidate_balls(X, R, neighbours)
    i = np.repeat(np.arange(len(X)), counts)
    value = np.linalg.norm(X[i] - S_d[j], axis=1) - R[j]
    c = clearance(i, j)
    foreign = c > margin if margin > 0 else np.zeros(len(i), dtype=bool)
    near = _row_minimum(np.where(foreign, np.inf, value - np.minimum(c, 0.0)), j, counts)
    return near, _row_minimum(np.where(foreign, value - np.minimum(margin, c - margin), np.inf), j, counts)


def _row_minimum(value, j, counts):
    """Per row of ``counts`` consecutive entries (every row non-empty): the smallest ``value`` and its ``j``."""
    starts = np.cumsum(counts) - counts
    smallest = np.minimum.reduceat(value, starts)
    hits = np.flatnonzero(value == np.repeat(smallest, counts))
    first = hits[np.searchsorted(hits, starts)]
    return smallest, j[first]


@dataclass
class FlowResult:
    """Outcome of :func:`medial_ball_flow`.

    Attributes
    ----------
    X : (n, 3) float
        The best iterate: fewest intersecting faces, then smallest error.
    best : int
        Its iteration (0: the start).
    intersecting : (k + 1,) int
        Intersecting faces (given reference pairs: those that do not intersect in the reference, S0's *new*)
    error : (k + 1,) float
        ``sum_i |f(x_i)|`` (Eq. 10's approximation, model units) at the same moments.
    step_seconds : (k,) float
        Seconds of each flow step (without the intersection test).
    seconds : float
        Wall seconds in all.
    """

    X: np.ndarray
    best: int
    intersecting: np.ndarray
    error: np.ndarray
    step_seconds: np.ndarray
    seconds: float

    @property
    def iterations(self):
        return len(self.step_seconds)


class MedialBallFlow:
    """The flow of Eq. 9 towards the union of the balls ``(S_d, R)`` over a prefactorized ``(I + L)``.

    Parameters
    ----------
    reconstruction : SkeletalReconstruction
        Of the rest mesh: gives ``F``, ``R``, the rest positions (for the margin) and ``(I + L)^-1``.
    S_d : (n, 3) float
        Deformed skeletal mesh: the anchors and ball centres (never moved).
    margin : float
        Clearance kept between parts that were apart at rest (model units; 0 = S1's flow).
    tau : float
        Step size of Eq. 9.
    neighbours : int
        Eq. 10's candidates per vertex at most (:func:`candidate_balls`); 0: all within ``R_i`` (S1).
    """

    def __init__(self, reconstruction, S_d, margin, tau=0.5, neighbours=64):
        self.rec, self.S_d, self.tau, self.margin, self.neighbours = reconstruction, S_d, tau, margin, neighbours

    def _clearance(self, i, j):
        rec = self.rec
        return np.linalg.norm(rec.V[i] - rec.S[j], axis=1) - rec.R[j]

    def _outward(self, X, p):
        """Unit directions from the ball centres ``S_d[p]`` to ``X``, (n, 3)."""
        d = X - self.S_d[p]
        return d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), TINY)

    def balls(self, X):
        """Eq. 10 at ``X``: the nearest and the nearest foreign balls; see :func:`nearest_balls`."""
        return nearest_balls(X, self.S_d, self.rec.R, self._clearance, self.margin, self.neighbours)

    def step(self, X, balls):
        """One step of Eq. 9 from ``X`` with its :meth:`balls`: new positions (n, 3).

        The speed is ``-g grad g - h grad h`` with ``g`` the nearest ball's value and ``h = min(0, .)`` the
        nearest foreign ball's (0 without a margin).
        """
        (g, p), (h, q) = balls
        h = np.minimum(np.where(np.isfinite(h), h, 0.0), 0.0)
        speed = -g[:, None] * self._outward(X, p) - h[:, None] * self._outward(X, q)
        return X + self.tau * self.rec.solve(speed)

    def run(self, X, max_iters=50, reference_pairs=None, ftol=0.01):
        """Flow from ``X`` until no (new) self-intersection remains and ``sum |f|`` stalls, or ``max_iters``.

        The intersection count of the flow is not monotone where parts interpenetrate deeply; the result is
        the best iterate (fewest intersecting faces, then smallest ``sum |f|``), not the last.

        Parameters
        ----------
        X : (n, 3) float
            Start (the reconstructed or target pose).
        max_iters : int
        reference_pairs : (q, 2) int, optional
            The reference's intersecting face pairs: their faces do not count.
        ftol : float or None
            Stop once intersection-free and ``sum |f|`` decreased by less than this fraction in a step;
            None: as soon as intersection-free.

        Returns
        -------
        FlowResult
        """
        start = time.perf_counter()
        balls = self.balls(X)
        counts, errors, steps = [self._intersecting(X, reference_pairs)], [np.abs(balls[0][0]).sum()], []
        best, X_best = 0, X
        for _ in range(max_iters):
            if counts[-1] == 0 and (ftol is None or len(errors) > 1 and errors[-1] >= (1.0 - ftol) * errors[-2]):
                break
            t0 = time.perf_counter()
            X = self.step(X, balls)
            balls = self.balls(X)
            steps.append(time.perf_counter() - t0)
            errors.append(np.abs(balls[0][0]).sum())
            counts.append(self._intersecting(X, reference_pairs))
            log.debug("flow %d: %d intersecting faces, sum|f| %.4g", len(steps), counts[-1], errors[-1])
            if (counts[-1], errors[-1]) < (counts[best], errors[best]):
                best, X_best = len(steps), X
        result = FlowResult(X_best, best, np.array(counts), np.array(errors), np.array(steps),
                            time.perf_counter() - start)
        log.info("medial-ball flow: %d iterations, intersecting faces %d -> %d (best, iteration %d), sum|f| %.4g -> "
                 "%.4g, %.2f s", result.iterations, counts[0], counts[best], best, errors[0], errors[best],
                 result.seconds)
        return result

    def _intersecting(self, X, reference_pairs):
        faces = intersecting_faces(self_intersecting_pairs(X, self.rec.F), len(self.rec.F))
        if reference_pairs is not None:  # as S0's verify: faces that do not intersect in the reference
            faces &= ~intersecting_faces(reference_pairs, len(self.rec.F))
        return int(faces.sum())


def medial_ball_flow(reconstruction, X, S_d, margin, tau=0.5, neighbours=64, max_iters=50, reference_pairs=None):
    """One-off :meth:`MedialBallFlow.run`; returns a :class:`FlowResult`."""
    return MedialBallFlow(reconstruction, S_d, margin, tau, neighbours).run(X, max_iters, reference_pairs)
