"""Mesh reconstruction from a deformed skeletal mesh with discrete differential coordinates (S1 §3, Eq. 3-5).

Every triangle ``T = (i, j, k)`` of the skeletal mesh carries a frame ``B = (t1 x t2, t1, t2)`` of its unit
edge directions ``t1 = (s_j - s_i)/|.|``, ``t2 = (s_k - s_i)/|.|``. The local transform ``A_T = B_d B_0^-1``
carries the radial vectors of the triangle's corners into the deformed skeleton, giving the fragmented
mesh (a triangle soup, Eq. 3) ``x_i^T = s_i^d + R_i A_T (x_i - s_i) / |A_T (x_i - s_i)|``. The deformed
mesh solves ``(I + L) x^d = y~`` (Eq. 5) with ``L`` the cotangent Laplacian of ``M`` (weights
``cot a + cot b``) and ``y~`` the graph Laplacian of the fragments plus their mean per vertex: with the rest
skeleton the fragments are ``M``'s own triangles and ``x^d = x``.

Where a skeletal triangle is degenerate or collapsed (a skeleton that degenerates to a curve, as on a
capsule, S1 §5), its frame is undefined or noise; :func:`frame_maps` then takes a caller-supplied map
(the rig's blended rotation).
"""

import logging
import time

import numpy as np
import scipy.sparse as sp

from posefix.mesh.geometry import face_areas
from posefix.mesh.laplacian import cotangent_laplacian
from posefix.mesh.sparse import factorized

log = logging.getLogger(__name__)


def triangle_frames(S, F):
    """Frames ``B = (t1 x t2, t1, t2)`` (columns) of the triangles of a skeletal mesh.

    Parameters
    ----------
    S : (n, 3) float
    F : (m, 3) int

    Returns
    -------
    B : (m, 3, 3) float
    sine : (m,) float
        ``|t1 x t2|``, the sine of the corner angle at ``F[:, 0]`` (0 for a zero-length edge).
    """
    e1, e2 = S[F[:, 1]] - S[F[:, 0]], S[F[:, 2]] - S[F[:, 0]]
    l1, l2 = np.linalg.norm(e1, axis=1), np.linalg.norm(e2, axis=1)
    ok = (l1 > 0) & (l2 > 0)
    t1 = e1 / np.where(ok, l1, 1.0)[:, None]
    t2 = e2 / np.where(ok, l2, 1.0)[:, None]
    v = np.cross(t1, t2)
    sine = np.where(ok, np.linalg.norm(v, axis=1), 0.0)
    return np.stack([v, t1, t2], axis=2), sine


def collapsed_faces(V, S, F, min_area=0.1):
    """Faces where the skeletal mesh collapsed: skeletal triangle area below ``min_area`` x the mesh triangle's.

    On a canal surface (a tube) the skeleton is a curve (S1 §5): the poles of a ring crowd on the axis and
    their triangles' frames are noise. A proper skeletal sheet keeps areas of the mesh's order (an
    ellipsoid's median ratio is 0.56, the demo limb's 0.024).

    Parameters
    ----------
    V, S : (n, 3) float
        Mesh and skeletal mesh.
    F : (m, 3) int

    Returns
    -------
    (m,) bool
    """
    return face_areas(S, F) < min_area * face_areas(V, F)


def frame_maps(S, S_d, F, fallback, min_sine=0.05, min_edge=1e-3, collapsed=None):
    """Local transforms ``A_T = B_d B_0^-1`` of the skeletal triangles (S1 §3, Fig. 5).

    Parameters
    ----------
    S, S_d : (n, 3) float
        Rest and deformed skeletal mesh.
    F : (m, 3) int
    fallback : (m, 3, 3) float
        Used where either frame is degenerate (sine below ``min_sine``, a too short edge) or ``collapsed``.
    min_sine : float
        Smallest ``|t1 x t2|`` of a usable frame.
    min_edge : float
        Shortest usable edge relative to the mean edge of ``S`` (shorter edges have unreliable directions).
    collapsed : (m,) bool, optional
        Faces that take the fallback in any case (:func:`collapsed_faces`).

    Returns
    -------
    A : (m, 3, 3) float
    degenerate : (m,) bool
    """
    B0, s0 = triangle_frames(S, F)
    Bd, sd = triangle_frames(S_d, F)
    edges = [np.linalg.norm(X[F[:, 1:]] - X[F[:, :1]], axis=2).min(axis=1) for X in (S, S_d)]
    shortest = min_edge * np.linalg.norm(S[F[:, 1]] - S[F[:, 0]], axis=1).mean()
    degenerate = (s0 < min_sine) | (sd < min_sine) | (edges[0] < shortest) | (edges[1] < shortest)
    if collapsed is not None:
        degenerate |= collapsed
    A = np.array(fallback, dtype=float, copy=True)
    good = ~degenerate
    A[good] = Bd[good] @ np.linalg.inv(B0[good])
    return A, degenerate


def corner_cotangents(V, F):
    """Cotangent of every corner angle of every triangle, (m, 3) float (column c: the angle at ``F[:, c]``)."""
    out = np.empty(F.shape)
    for c in range(3):
        a, b = V[F[:, (c + 1) % 3]] - V[F[:, c]], V[F[:, (c + 2) % 3]] - V[F[:, c]]
        out[:, c] = np.einsum("ij,ij->i", a, b) / np.linalg.norm(np.cross(a, b), axis=1)
    return out


class SkeletalReconstruction:
    """Reconstruct deformed poses of ``M`` from deformed skeletal meshes; ``(I + L)`` is factorized once.

    Parameters
    ----------
    V : (n, 3) float
        The mesh ``M`` (non-degenerate faces).
    F : (m, 3) int
    S : (n, 3) float
        Its skeletal mesh; radii ``R = |V - S|``.
    min_area : float
        Faces whose skeletal triangle is smaller than this x theirs take the fallback frame
        (:func:`collapsed_faces`).

    Examples
    --------
    >>> rec = SkeletalReconstruction(V, F, S)            # doctest: +SKIP
    >>> X = rec.reconstruct(S_d, fallback_maps)           # doctest: +SKIP
    """

    def __init__(self, V, F, S, min_area=0.1):
        start = time.perf_counter()
        self.V, self.F, self.S = V, F, S
        self.collapsed = collapsed_faces(V, S, F, min_area)
        self.R = np.linalg.norm(V - S, axis=1)
        self.radial = (V - S) / np.where(self.R > 0, self.R, 1.0)[:, None]
        self.cot = corner_cotangents(V, F)
        self.count = np.bincount(F.ravel(), minlength=len(V)).astype(float)
        self.L = 2.0 * cotangent_laplacian(V, F)
        self._solver = factorized(sp.identity(len(V), format="csc") + self.L, "MMD_AT_PLUS_A", symmetric=True)
        log.debug("(I + L) of %d vertices factorized in %.3f s", len(V), time.perf_counter() - start)

    def solve(self, rhs):
        """``(I + L)^-1 rhs`` for (n,) or (n, k) float."""
        return self._solver.solve(rhs)

    def fragments(self, S_d, maps):
        """The fragmented mesh ``M_F`` (Eq. 3): corner positions (m, 3, 3) float, ``[f, c]`` for ``F[f, c]``."""
        F = self.F
        r = np.einsum("fij,fcj->fci", maps, self.radial[F])
        r /= np.linalg.norm(r, axis=2, keepdims=True)
        return S_d[F] + self.R[F][..., None] * r

    def right_hand_side(self, X_F):
        """``y~`` of Eq. 5 from corner positions (m, 3, 3): fragment Laplacian plus fragment mean, (n, 3)."""
        F, cot = self.F, self.cot
        y = np.zeros((len(self.V), 3))
        for c in range(3):
            b, d = (c + 1) % 3, (c + 2) % 3
            term = (cot[:, d, None] * (X_F[:, c] - X_F[:, b]) + cot[:, b, None] * (X_F[:, c] - X_F[:, d])
                    + X_F[:, c] / self.count[F[:, c], None])
            np.add.at(y, F[:, c], term)
        return y

    def reconstruct(self, S_d, fallback, min_sine=0.05):
        """The deformed mesh ``x^d`` for the deformed skeleton ``S_d`` (n, 3); see :func:`frame_maps`."""
        maps, degenerate = frame_maps(self.S, S_d, self.F, fallback, min_sine, collapsed=self.collapsed)
        log.debug("%d of %d skeletal triangles degenerate (fallback maps)", degenerate.sum(), len(self.F))
        return self.solve(self.right_hand_side(self.fragments(S_d, maps)))


def reconstruct(V, F, S, S_d, fallback, min_sine=0.05, min_area=0.1):
    """One-off :meth:`SkeletalReconstruction.reconstruct`: the deformed mesh (n, 3) for ``S_d``."""
    return SkeletalReconstruction(V, F, S, min_area).reconstruct(S_d, fallback, min_sine)
