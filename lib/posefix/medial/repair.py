"""The medial repair: S1's medial balls carried into a target pose, its damaged region rebuilt on them, the flow.

A pose library has no stick figure, so the deformed skeletal mesh ``S_d`` of a target comes from the
reference's skeletal mesh ``(S, R)`` and the target itself:

1. **Rotations.** Every vertex gets the rotation ``Q_i`` of the target's local frame change: the polar factor
   of the area-weighted mean of ``B_d B_0^-1`` over its triangles (S1's frame change, applied to the mesh's
   triangles instead of the skeleton's).
2. **Damaged region** ``D``: the vertices within ``reach`` ball radii (along the reference's edges) of a vertex of
   a new intersecting face. Where parts interpenetrate, the target's frames are folded: inside ``D`` the
   rotations are replaced by the harmonic blend of those around it (then projected back onto rotations).
3. **Deformed skeleton.** Outside ``D`` each ball is carried rigidly with its vertex,
   ``s_i^d = x_i - Q_i (x_i^0 - s_i)`` (so the ball still touches its vertex); inside ``D`` the skeleton bends
   smoothly through the joint: the Poisson equation ``L s^d = div(Q (s_j - s_i))`` over the mesh graph, with
   the carried centres around ``D`` as boundary values.
4. **Rebuild.** ``D`` is reconstructed from the reference's edges turned by the blended rotations (S1's
   differential coordinates, Eq. 3-5: a cotangent Poisson solve), the target outside ``D`` as boundary
   values: the skeleton-driven pose of the damaged part. The region grows (``reach = 1, 2, ...``) until this
   start has no new intersection.
5. **Flow.** S1's medial-ball flow (:class:`~posefix.medial.flow.MedialBallFlow`) from that start, with
   ``S_d`` as anchors, until no new intersection remains or ``max_iters``.

Measured on the demo library (bends of 120-150 degrees): S1's flow started from the target itself, with the
balls carried by the target's frames, *adds* intersections (demo-01: 129 -> 536 new intersecting faces in
50 iterations) because folded parts are pushed out of the nearest balls, which belong to the other part;
the rebuild leaves none on any demo pose, the flow is only needed where the rebuilt start still intersects.
"""

import logging
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from posefix.mesh.contacts import edge_graph
from posefix.mesh.geometry import face_areas
from posefix.mesh.harmonic import harmonic_extension
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.mesh.rotations import polar_decomposition
from posefix.mesh.sparse import factorized
from posefix.mesh.topology import vertex_adjacency
from posefix.medial.flow import FlowResult, MedialBallFlow
from posefix.medial.reconstruction import SkeletalReconstruction, triangle_frames

log = logging.getLogger(__name__)


@dataclass
class MedialRepairResult:
    """Outcome of :meth:`MedialRepair.repair`.

    Attributes
    ----------
    X : (n, 3) float
        The repaired pose.
    S_d : (n, 3) float
        The deformed skeletal mesh (ball centres; radii are the reference's).
    free : (n, 3) bool
        The damaged region ``D`` that was rebuilt.
    reach : float
        Its reach in ball radii (0: nothing was damaged).
    target_faces : int
        New intersecting faces of the target.
    start_faces : int
        New intersecting faces of the rebuilt start of the flow.
    flow : FlowResult
    seconds : float
    """

    X: np.ndarray
    S_d: np.ndarray
    free: np.ndarray
    reach: float
    target_faces: int
    start_faces: int
    flow: FlowResult
    seconds: float


class MedialRepair:
    """Repair target poses of a reference mesh with its medial balls (see the module text).

    Parameters
    ----------
    V : (n, 3) float
        The reference mesh ``M``; ``F`` (m, 3) int its faces.
    S : (n, 3) float
        Its skeletal mesh (:func:`~posefix.medial.skeletal_mesh.skeletal_mesh`); radii ``R = |V - S|``.
    margin : float
        Clearance kept by the flow between parts apart at rest (model units).
    tau : float
        Step size of the flow (S1 Eq. 9).
    neighbours : int
        Candidate balls per vertex in the flow.
    max_reach : int
        Largest damaged region tried, in ball radii (1, 2, ... up to it).
    min_area : float
        See :class:`~posefix.medial.reconstruction.SkeletalReconstruction`.

    Examples
    --------
    >>> repair = MedialRepair(V, F, skeleton.S, margin=0.01 * d)   # doctest: +SKIP
    >>> result = repair.repair(X_target)                              # doctest: +SKIP
    """

    def __init__(self, V, F, S, margin, tau=0.5, neighbours=64, max_reach=4, min_area=0.1):
        self.rec = SkeletalReconstruction(V, F, S, min_area)
        self.V, self.F, self.S, self.R = V, F, S, self.rec.R
        self.margin, self.tau, self.neighbours, self.max_reach = margin, tau, neighbours, max_reach
        self.adjacency = vertex_adjacency(F, len(V))
        self.graph = edge_graph(V, F)
        self.reference_pairs = self_intersecting_pairs(V, F)
        self.reference_faces = intersecting_faces(self.reference_pairs, len(F))
        self._frames_inv = np.linalg.inv(triangle_frames(V, F)[0])
        self._area = face_areas(V, F)
        self._cotangent = (0.5 * self.rec.L).tocsr()  # cot alpha + cot beta over 2 per edge, positive diagonal

    def new_faces(self, X):
        """Faces of ``X`` that intersect and do not intersect in the reference (S0's *new*), (m,) bool."""
        return self.all_faces(X) & ~self.reference_faces

    def all_faces(self, X):
        """Faces of ``X`` in any intersecting pair, (m,) bool."""
        return intersecting_faces(self_intersecting_pairs(X, self.F), len(self.F))

    def rotations(self, X):
        """Per-vertex rotations ``Q`` (n, 3, 3) of the local frame change from the reference to ``X``."""
        maps = triangle_frames(X, self.F)[0] @ self._frames_inv * self._area[:, None, None]
        J = np.zeros((len(self.V), 3, 3))
        for c in range(3):
            np.add.at(J, self.F[:, c], maps)
        return polar_decomposition(J)[0]

    def damaged(self, faces, reach):
        """Vertices within ``reach`` ball radii (graph distance at rest) of the vertices of ``faces``, (n,) bool."""
        seeds = np.unique(self.F[faces])
        free = np.zeros(len(self.V), dtype=bool)
        if len(seeds) == 0:
            return free
        limit = reach * float(self.R[seeds].max())
        dist, _, source = dijkstra(self.graph, indices=seeds, limit=limit, min_only=True, return_predecessors=True)
        near = np.isfinite(dist)
        free[near] = dist[near] <= reach * self.R[source[near]]
        return free

    def skeleton(self, X, Q, free):
        """The deformed skeletal mesh ``S_d`` (n, 3) and the rotations, blended inside ``free`` (n, 3, 3)."""
        radial = self.V - self.S
        if free.any():
            Q = Q.copy()
            Q[free] = polar_decomposition(harmonic_extension(self.adjacency, Q.reshape(-1, 9), ~free)
                                          .reshape(-1, 3, 3)[free])[0]
        S_d = X - np.einsum("nij,nj->ni", Q, radial)
        if free.any():
            S_d[free] = self._bend(S_d, Q, free)
        return S_d, Q

    def _bend(self, S_d, Q, free):
        """Skeleton inside ``free``: ``L s = div(Q ds)`` with the carried centres outside as boundary values."""
        A = sp.csr_matrix(self.adjacency, dtype=np.float64).tocoo()
        i, j = A.row, A.col
        guide = 0.5 * np.einsum("kab,kb->ka", Q[i] + Q[j], self.S[i] - self.S[j])
        rhs = np.zeros((len(self.V), 3))
        np.add.at(rhs, i, guide)
        L = (sp.diags(np.asarray(A.sum(axis=1)).ravel()) - A).tocsr()
        u, k = np.flatnonzero(free), np.flatnonzero(~free)
        solver = factorized(L[u][:, u].tocsc(), "MMD_AT_PLUS_A", symmetric=True)
        return solver.solve(rhs[u] - L[u][:, k] @ S_d[k])

    def rebuild(self, X, free, Q):
        """``X`` with ``free`` re-solved from the rotated rest edges, (n, 3).

        ``L x = div(Q dV)`` on ``free`` (cotangent ``L``, edge rotations the mean of their ends'), ``X`` outside
        as boundary values: S1's differential-coordinate reconstruction (Eq. 3-5) of the damaged region.
        """
        Y = X.copy()
        if not free.any():
            return Y
        L = self._cotangent
        A = (sp.diags(L.diagonal()) - L).tocoo()
        i, j = A.row, A.col
        guide = A.data[:, None] * 0.5 * np.einsum("kab,kb->ka", Q[i] + Q[j], self.V[i] - self.V[j])
        rhs = np.zeros((len(self.V), 3))
        np.add.at(rhs, i, guide)
        u, k = np.flatnonzero(free), np.flatnonzero(~free)
        solver = factorized(L[u][:, u].tocsc(), "MMD_AT_PLUS_A", symmetric=True)
        Y[u] = solver.solve(rhs[u] - L[u][:, k] @ X[k])
        return Y

    def repair(self, X, max_iters=50):
        """Repair the target ``X`` (n, 3); returns a :class:`MedialRepairResult`."""
        start = time.perf_counter()
        faces = self.new_faces(X)
        Q = self.rotations(X)
        tries = [(0, np.zeros(len(X), dtype=bool))] if not faces.any() else []
        tries += [(r, self.damaged(faces, r)) for r in range(1, self.max_reach + 1) if faces.any()]
        best = None
        for reach, free in tries:
            S_d, Q_d = self.skeleton(X, Q, free)
            Y = self.rebuild(X, free, Q_d)
            count = int(self.new_faces(Y).sum())
            log.info("reach %d ball radii: %d damaged vertices, %d new intersecting faces after the rebuild",
                     reach, free.sum(), count)
            if best is None or count < best[0]:
                best = (count, reach, free, S_d, Y)
            if count == 0:
                break
        count, reach, free, S_d, Y = best
        flow = MedialBallFlow(self.rec, S_d, self.margin, self.tau, self.neighbours).run(
            Y, max_iters, self.reference_pairs, ftol=None)
        return MedialRepairResult(flow.X, S_d, free, float(reach), int(faces.sum()), count, flow,
                                  time.perf_counter() - start)


def medial_repair(V, F, S, X, margin, max_iters=50, **options):
    """One-off :meth:`MedialRepair.repair` of the target ``X`` (``options``: :class:`MedialRepair`'s ``tau``,
    ``neighbours``, ``max_reach``, ``min_area``); returns a :class:`MedialRepairResult`."""
    return MedialRepair(V, F, S, margin, **options).repair(X, max_iters)
