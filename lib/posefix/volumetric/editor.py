"""S4's iterative tetrahedral Laplacian editing (§2.3): linear solve, per-tet rotations, rigid regions, repeat.

One iteration: solve ``L x = delta`` with the handles fixed, extract every tet's rotation ``R_j`` from its
transformation ``T_j`` (Eq. 2.6-2.8), give every rigid region its mean rotation, and rebuild
``delta = G^T D g`` from the rotated gradients ``g_j = R_j^T`` (Eq. 2.5). ``L`` is reduced by the handles
(and the rigid regions) and factorized once per :class:`VolumetricEditor`.

Rigid regions are exact here: their vertices move as ``c + R (x^0 - centroid)`` with the region's mean
rotation ``R`` and one unknown centre ``c`` each (S4 only gives their tets the same rotation, which leaves
them rigid up to the least-squares residual).
"""

import logging
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from posefix.mesh.harmonic import harmonic_extension
from posefix.mesh.rotations import cofactors, polar_decomposition, polar_rotations, rotation_exp, rotation_log
from posefix.mesh.sparse import factorized
from posefix.volumetric.embedding import barycentric_embedding
from posefix.volumetric.operators import differential_coordinates, tet_adjacency, tet_gradient_operator, tet_mass

log = logging.getLogger(__name__)

ROTATIONS = ("polar", "average")
"""Rotation extraction: the polar factor (scaled Newton, :func:`~posefix.mesh.rotations.polar_rotations`), or
S4's averaging with the inverse transpose (Eq. 2.8: three steps and row normalisation)."""


def averaged_rotations(A, steps=3):
    """S4 Eq. 2.8: ``H <- (H + H^-T) / 2`` ``steps`` times, rows normalized, reflections negated, (t, 3, 3)."""
    H = A.copy()
    for _ in range(steps):
        C = cofactors(H)
        H = 0.5 * (H + C / np.einsum("mij,mij->m", H[:, :1], C[:, :1])[:, None, None])
    H /= np.linalg.norm(H, axis=2, keepdims=True)
    H[np.linalg.det(H) < 0] *= -1.0
    return H


def extract_rotations(A, method="polar"):
    """Rotations (t, 3, 3) of the per-tet transformations ``A`` (t, 3, 3): see :data:`ROTATIONS`."""
    if method == "polar":
        return polar_rotations(A)
    if method == "average":
        return averaged_rotations(A)
    raise ValueError(f"rotation extraction {method!r}: one of {ROTATIONS}")


@dataclass
class EditResult:
    """Outcome of :meth:`VolumetricEditor.solve`.

    Attributes
    ----------
    X : (n, 3) float
        Deformed tet-mesh vertices.
    rotations : (t, 3, 3) float
        Per-tet rotations of the last iteration (the identity after a purely linear solve).
    shear : (k + 1,) float
        Volume-weighted mean ``|T_j - R_j|`` (Frobenius) after every solve: how far the tets are from rigid.
    seconds : float
    """

    X: np.ndarray
    rotations: np.ndarray
    shear: np.ndarray
    seconds: float


@dataclass(frozen=True)
class PointHandles:
    """Point handles of a :class:`VolumetricEditor` (S4 §2.3.1): fixed linear combinations of the vertices of the
    tet that contains each point (:func:`barycentric_embedding`).

    Attributes
    ----------
    positions : (p, 3) float
        Rest positions, anywhere inside or near the mesh (e.g. motion-capture markers).
    weight : float, optional
        None: held exactly at their targets by Lagrange multipliers. Else soft: ``weight`` times the mean
        diagonal of ``L`` weighs ``|C x - p|^2`` against the Laplacian energy; needed when the points
        over-determine the tets (more points than a tet has degrees of freedom, e.g. a whole surface region).
    """

    positions: np.ndarray
    weight: float | None = None


class VolumetricEditor:
    """Deform a tet mesh by vertex handles (S4 §2.3); ``L`` is reduced and factorized once.

    Parameters
    ----------
    X : (n, 3) float
        Rest positions of the tet mesh; ``T`` (t, 4) int its positively oriented tets.
    handles : (h,) int
        Vertices whose positions are given in :meth:`solve` (at least one, or a rigid region).
    rigid : sequence of (k,) int, optional
        Rigid regions as tet ids: each moves rigidly (vertices of different regions must not overlap, and
        handles must not lie in a region).
    stiffness : (t,) float, optional
        Per-tet stiffness (S4 scales ``G_j`` and ``g_j``; here their squares scale the volumes).
    rotation : str
        Rotation extraction, see :data:`ROTATIONS`.
    regions : sequence of (k,) int, optional
        Region handles as tet ids (S4 §2.3.1): their vertices must be among ``handles``; :meth:`solve` can
        impose their orientation, which S4's rotation interpolation then spreads over the other tets.
    points : PointHandles, optional
        Point handles anywhere inside or near the mesh (S4 §2.3.1, e.g. motion-capture markers).
    Examples
    --------
    >>> editor = VolumetricEditor(X, T, handles=np.r_[fixed, moved])              # doctest: +SKIP
    >>> result = editor.solve(np.r_[X[fixed], X[moved] + [0, 1, 0]], iterations=10)  # doctest: +SKIP
    """

    def __init__(self, X, T, handles, rigid=(), stiffness=None, rotation="polar", regions=(), points=None):
        points, point_weight = (None, None) if points is None else (points.positions, points.weight)
        if rotation not in ROTATIONS:
            raise ValueError(f"rotation extraction {rotation!r}: one of {ROTATIONS}")
        self.X, self.T, self.rotation = np.asarray(X, dtype=float), np.asarray(T), rotation
        self.handles = np.asarray(handles, dtype=np.int64)
        self.rigid = [np.asarray(r, dtype=np.int64) for r in rigid]
        self.regions = [np.asarray(r, dtype=np.int64) for r in regions]
        if any(not np.isin(self.T[r], self.handles).all() for r in self.regions):
            raise ValueError("a region handle has vertices that are not handles")
        self._adjacency = tet_adjacency(self.T) if self.regions else None
        self.G = tet_gradient_operator(self.X, self.T)
        self.D = tet_mass(self.X, self.T, None if stiffness is None else np.asarray(stiffness) ** 2)
        self._volumes = self.D.diagonal()[::3]
        self._setup_unknowns(points)
        L = (self.G.T @ self.D @ self.G).tocsr()
        self._L = L
        self.C = self._point_rows(points)
        self.point_weight = None if point_weight is None else point_weight * L.diagonal().mean()
        if self.C is not None and self.point_weight is not None:
            L = L + self.point_weight * (self.C.T @ self.C)
        A = (self.P.T @ L @ self.P).tocsc()
        if self.C is None or self.point_weight is not None:
            self._solver = factorized(A, "MMD_AT_PLUS_A", symmetric=True)
        else:  # KKT system [[A, (C P)^T], [C P, 0]]: symmetric indefinite
            CP = (self.C @ self.P).tocsr()
            self._solver = factorized(sp.bmat([[A, CP.T], [CP, None]]).tocsc())

    def _point_rows(self, points):
        """``C`` (p, n) sparse: the barycentric rows of the point handles (None without)."""
        if points is None or len(points) == 0:
            return None
        tets, weights = barycentric_embedding(self.X, self.T, np.asarray(points, dtype=float).reshape(-1, 3))
        rows = np.repeat(np.arange(len(tets)), 4)
        return sp.csr_matrix((weights.ravel(), (rows, self.T[tets].ravel())), shape=(len(tets), len(self.X)))

    def _setup_unknowns(self, points):
        """``x = P y + b``: free vertices and one centre per rigid region are the unknowns ``y``."""
        n = len(self.X)
        owner = np.full(n, -1)  # -1 free, -2 handle, r >= 0 rigid region r
        owner[self.handles] = -2
        self.region_vertices = []
        for r, tets in enumerate(self.rigid):
            verts = np.unique(self.T[tets])
            if np.any(owner[verts] != -1):
                raise ValueError(f"rigid region {r} overlaps a handle or another rigid region")
            owner[verts] = r
            self.region_vertices.append(verts)
        if len(self.handles) == 0 and not self.rigid and points is None:
            raise ValueError("no handle and no rigid region: the position is undetermined")
        free = np.flatnonzero(owner == -1)
        columns = np.full(n, -1)
        columns[free] = np.arange(len(free))
        for r, verts in enumerate(self.region_vertices):
            columns[verts] = len(free) + r
        rows = np.flatnonzero(columns >= 0)
        self.P = sp.csr_matrix((np.ones(len(rows)), (rows, columns[rows])), shape=(n, len(free) + len(self.rigid)))
        self.free = free

    def _offsets(self, targets, rotations):
        """``b``: handle targets, and each rigid region's rest shape turned by its rotation about its centre."""
        b = np.zeros_like(self.X)
        b[self.handles] = targets
        for tets, verts in zip(self.rigid, self.region_vertices):
            rest = self.X[verts] - self.X[verts].mean(axis=0)
            b[verts] = rest @ rotations[tets[0]].T
        return b

    def linear_solve(self, targets, rotations, point_targets=None):
        """Positions (n, 3) for the handle ``targets`` (h, 3), per-tet ``rotations`` (t, 3, 3) and the point
        handles' targets (p, 3)."""
        delta = differential_coordinates(self.G, self.D, rotations.transpose(0, 2, 1))
        b = self._offsets(targets, rotations)
        rhs = delta - self._L @ b
        if self.C is not None:
            p = np.asarray(point_targets, dtype=float).reshape(-1, 3)
            if self.point_weight is None:
                rhs = np.vstack([np.asarray(self.P.T @ rhs), p - self.C @ b])
            else:
                rhs = np.asarray(self.P.T @ (rhs + self.point_weight * (self.C.T @ (p - self.C @ b))))
        else:
            rhs = np.asarray(self.P.T @ rhs)
        y = self._solver.solve(rhs)[:self.P.shape[1]]
        return self.P @ y + b

    def transformations(self, X):
        """Per-tet linear maps ``T_j`` (t, 3, 3) from the rest tets to ``X`` (S4 Eq. 2.6, column vectors)."""
        return (self.G @ X).reshape(-1, 3, 3).transpose(0, 2, 1)

    def rotations(self, A):
        """Per-tet rotations of the maps ``A``, rigid regions given their (volume-weighted) mean, (t, 3, 3)."""
        R = extract_rotations(A, self.rotation)
        for tets in self.rigid:
            R[tets] = polar_decomposition((self._volumes[tets, None, None] * R[tets]).sum(axis=0)[None])[0][0]
        return R

    def interpolate_rotations(self, R, region_rotations):
        """S4's rotation interpolation: the region handles turned to ``region_rotations`` (r, 3, 3), the change
        relative to their current estimate in ``R`` (the previous frame's) blended harmonically over the tets as
        rotation vectors and applied to ``R``: only the small change of one frame is averaged, S4's fix for
        turns beyond 180 degrees."""
        known = np.zeros(len(self.T), dtype=bool)
        omega = np.zeros((len(self.T), 3))
        for tets, target in zip(self.regions, region_rotations):
            current = polar_decomposition(R[tets].sum(axis=0)[None])[0][0]
            omega[tets] = rotation_log((target @ current.T)[None])[0]
            known[tets] = True
        R = rotation_exp(harmonic_extension(self._adjacency, omega, known)) @ R
        for tets, target in zip(self.regions, region_rotations):
            R[tets] = target
        return R

    def solve(self, targets, iterations=10, warm_start=None, region_rotations=None, point_targets=None):
        """Deform towards handle ``targets`` (h, 3): the linear solve, then ``iterations`` S4 iterations.

        ``warm_start``: per-tet rotations (t, 3, 3) to start from (e.g. the previous result's, for the next
        frame of an interaction); default the identity. ``region_rotations`` (r, 3, 3): orientations of the
        region handles; their change from ``warm_start`` is interpolated over the mesh first. ``point_targets``
        (p, 3): where the point handles go (required with point handles).
        """
        if (self.C is None) != (point_targets is None):
            raise ValueError("point_targets are needed exactly when the editor has point handles")
        start = time.perf_counter()
        targets = np.asarray(targets, dtype=float).reshape(-1, 3)
        R = np.broadcast_to(np.eye(3), (len(self.T), 3, 3)).copy() if warm_start is None else warm_start.copy()
        if region_rotations is not None:
            R = self.interpolate_rotations(R, region_rotations)
        shear = []
        for k in range(iterations + 1):
            X = self.linear_solve(targets, R, point_targets)
            A = self.transformations(X)
            R_new = self.rotations(A)
            shear.append(float(np.average(np.linalg.norm(A - R_new, axis=(1, 2)), weights=self._volumes)))
            if k < iterations:
                R = R_new
        log.debug("%d iterations, mean |T - R| %.3g -> %.3g", iterations, shear[0], shear[-1])
        return EditResult(X, R, np.array(shear), time.perf_counter() - start)


def edit(X, T, handles, targets, iterations=10, rigid=(), stiffness=None, rotation="polar"):
    """One-off :meth:`VolumetricEditor.solve`: an :class:`EditResult`."""
    return VolumetricEditor(X, T, handles, rigid, stiffness, rotation).solve(targets, iterations)
