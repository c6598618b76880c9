"""Which medial-ball centres are wrong: outside the surface, or with a ball that crosses it.

A centre ``s_i`` with radius ``R_i`` of a medial ball must lie inside the solid (generalized winding
number at least 0.5, so self-intersecting, open and non-manifold meshes are handled; by default its
far-field approximation) and its ball must be empty: the distance from ``s_i`` to the surface is at
least ``R_i`` (up to ``tol``), i.e. the ball is not larger than the local feature size. The distance
is exact (:func:`surface_distance_below`), not to the faces around the nearest vertices only.
"""

import logging
import time
from dataclasses import dataclass

import numpy as np
from posefix.mesh.distance import surface_distance_below
from posefix.mesh.winding import fast_winding_numbers, winding_numbers

log = logging.getLogger(__name__)

@dataclass(frozen=True)
class BadCentres:
    """Classification of medial centres; every array is (n,).

    Attributes
    ----------
    nonfinite : bool
        The centre or radius is NaN or infinite (e.g. no pole found).
    outside : bool
        Finite, with winding number below 0.5.
    crossing : bool
        Finite and inside, but the ball crosses the surface: distance to it below ``(1 - tol) R``.
    winding : float
        Winding number of the centre (NaN where not finite).
    clearance : float
        Distance from the centre to the surface over ``R``, capped at 1 (NaN where not finite).
    """

    nonfinite: np.ndarray
    outside: np.ndarray
    crossing: np.ndarray
    winding: np.ndarray
    clearance: np.ndarray

    @property
    def bad(self):
        """(n,) bool: any of the three."""
        return self.nonfinite | self.outside | self.crossing

    def counts(self):
        """Numbers of non-finite, outside, crossing and bad centres, a dict of int."""
        return {"nonfinite": int(self.nonfinite.sum()), "outside": int(self.outside.sum()),
                "crossing": int(self.crossing.sum()), "bad": int(self.bad.sum())}


def bad_centres(V, F, S, R, tol=0.5, exact_winding=False):
    """Classify medial-ball centres of a mesh as good or bad.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
        The surface; may be open, non-manifold or self-intersecting.
    S : (k, 3) float
        Ball centres (NaN allowed).
    R : (k,) float
        Ball radii, in the units of ``V``.
    tol : float
        Relative slack of the crossing test: a ball crosses when the surface comes closer than
        ``(1 - tol) R`` to its centre (a discrete pole's ball may dip slightly into the faces
        between the vertices it touches). 0.5 (a ball at most twice the empty one): on the library
        references the clearance of the poles has its median at 0.89-0.95 (the faces between the
        samples dip into the balls), so a small ``tol`` flags most of them (lion: 86 % at 0.02).
    exact_winding : bool
        Use :func:`~posefix.mesh.winding.winding_numbers` instead of the far-field approximation
        :func:`~posefix.mesh.winding.fast_winding_numbers` (error below 0.03 measured; 19x faster
        on the 60k-vertex kids mesh: about 5 s instead of 95 s).

    Returns
    -------
    BadCentres
    """
    start = time.perf_counter()
    S, R = np.asarray(S, dtype=np.float64), np.asarray(R, dtype=np.float64)
    nonfinite = ~(np.isfinite(S).all(axis=1) & np.isfinite(R))
    ok = np.flatnonzero(~nonfinite)
    winding = np.full(len(S), np.nan)
    winding[ok] = (winding_numbers if exact_winding else fast_winding_numbers)(V, F, S[ok])
    outside = ~nonfinite & (winding < 0.5)
    clearance = np.full(len(S), np.nan)
    clearance[ok] = surface_distance_below(V, F, S[ok], R[ok]) / np.where(R[ok] > 0, R[ok], np.inf)
    clearance[ok] = np.minimum(clearance[ok], 1.0)
    crossing = ~nonfinite & ~outside & (clearance < 1.0 - tol)
    result = BadCentres(nonfinite, outside, crossing, winding, clearance)
    log.info("bad medial centres of %d: %s, %.2f s", len(S), result.counts(), time.perf_counter() - start)
    return result
