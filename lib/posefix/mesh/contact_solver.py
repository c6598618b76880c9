"""Contact-aware motion toward per-vertex goals that never leaves the intersection-free set (IPC).

Incremental Potential Contact (Li et al. 2020) on the IPC Toolkit (``ipctk``): a log barrier on the
distances below ``dhat`` between non-adjacent primitives (vertex-face and edge-edge pairs) keeps every
contact open, and a continuous-collision-detection (CCD) bound on every line-search step makes sure no
step passes through one. Minimized, by Newton's method with the PSD-projected barrier Hessian::

    E(x) = 1/2 sum_i w_i a_i |x_i - g_i|^2 + 1/2 l^4 (x - s)^T L^T M^-1 L (x - s) + kappa B(x)

``g``: the goals, ``s``: the shape the smoothness term keeps (the goals by default), ``w``: per-vertex
weights, ``a``: vertex areas over their mean, ``L``/``M``: the cotangent Laplacian and lumped areas of the
reference (so the bi-Laplacian smoothness term spreads a contact's push over about the smoothing length
``l``, and a rigid motion of the goals costs nothing), ``kappa``: IPC's adaptive barrier stiffness.

The reference may intersect itself. Its intersecting face pairs are *tolerated*: the edge-edge and
face-vertex pairs of each (9 and 6) are removed from the broad phase's candidates before the barrier and the
CCD see them, and no other primitive pair is: a face that does not intersect in the reference never comes to
intersect anything, and two tolerated faces of different intersection sites cannot pass through each other.
``ipctk``'s vertex filter alone would silence every pair whose vertices all belong to tolerated faces (a
primitive next to them too), so the region's own broad phase gives those pairs back, less the tolerated ones:
the Python work is the tolerated region's, not the mesh's.

:class:`ContactSolver` precomputes per reference; :meth:`ContactSolver.compute_pose` moves one pose toward its
goals, :meth:`ContactSolver.compute_path` carries one through a sequence of poses (key frames, path-line samples).
"""

import logging
import time
from contextlib import contextmanager
from dataclasses import dataclass, field

import ipctk
import numpy as np
import scipy.linalg
import scipy.sparse as sp

from posefix.mesh.geometry import bbox_diagonal, vertex_areas
from posefix.mesh.laplacian import cotangent_laplacian
from posefix.mesh.rounding import float32_gap
from posefix.mesh.sparse import cholesky_factorized, factorized, fill_reducing_order
from posefix.mesh.tolerances import ROUNDOFF, TINY

log = logging.getLogger(__name__)

_PSD = ipctk.PSDProjectionMethod.CLAMP

_CCD = ipctk.AdditiveCCD()
"""Additive CCD (Li et al. 2021, conservative advancement): on the lion poses about half the time and two thirds
of the Newton iterations of Tight-Inclusion CCD (1e-6 tolerance, 1000 iterations), both conservative."""

GAP_STEPS = 8
"""Pushes of :meth:`ContactSolver.keep_gap` at most (each moves a vertex of a pair closer than the gap by the gap)."""

WAYPOINT_TOLERANCE = 1e-3
"""Newton's stopping step / d on the waypoints of :meth:`ContactSolver.compute_path` (all but the last)."""


@dataclass(frozen=True)
class ContactSettings:
    """How the contact solver moves a pose; lengths relative to the reference's bounding-box diagonal ``d``.

    Attributes
    ----------
    dhat : float
        Largest barrier activation distance / d (IPC's usual 1e-3). The solver takes half the reference's
        clearance (its smallest distance between non-adjacent primitives that are neither tolerated nor
        touching) when that is smaller, so that the barrier does not push apart parts that are close at rest.
    dhat_min : float
        Smallest barrier activation distance / d: parts of the reference closer than twice this (lion: 753 pairs
        below 5e-4 d, the closest 4.5e-7 d apart) feel the barrier at rest and are held about where they are.
    touching : float
        Primitive pairs of the reference closer than ``touching * d`` are tolerated (parts touching at rest:
        the barrier cannot start from a distance of 0).
    smoothing : float
        Smoothing length ``l`` / d of the bi-Laplacian term.
    tolerance : float
        Newton stops when its step moves no vertex farther than ``tolerance * d``.
    max_iterations : int
        Newton iterations at most: where many contacts hold the free region, the elastic finish creeps along them
        (cat-04, cat-08: converged in 275 and 248).

    Each field's ``metadata`` (its help, unit and bounds) is the one declaration of the setting: the stages' options,
    config ``contact``'s schema and docs/configuration.md come from it (``posefix.workflow.settings``).
    """

    dhat: float = field(default=1e-3, metadata={
        "help": "largest barrier activation distance (half the reference's clearance when smaller)", "unit": "d",
        "exclusiveMinimum": 0})
    dhat_min: float = field(default=2e-4, metadata={
        "help": "smallest barrier activation distance (parts closer at rest feel the barrier)", "unit": "d",
        "exclusiveMinimum": 0})
    touching: float = field(default=1e-9, metadata={
        "help": "pairs of the reference closer than this are tolerated (touching at rest)", "unit": "d", "minimum": 0})
    smoothing: float = field(default=0.02, metadata={
        "help": "smoothing length of the bi-Laplacian term", "unit": "d", "minimum": 0})
    tolerance: float = field(default=1e-3, metadata={
        "help": "Newton stops when its step moves no vertex farther than this", "unit": "d", "exclusiveMinimum": 0})
    max_iterations: int = field(default=400, metadata={
        "help": "Newton iterations at most per solve", "minimum": 1})


@dataclass
class ContactResult:
    """A pose moved by :meth:`ContactSolver.compute_pose`.

    Attributes
    ----------
    X : (n, 3) float
        Positions, intersection-free up to the tolerated faces' own intersections.
    converged : bool
        Newton's step fell below the tolerance (else the iterations ran out or the line search stalled).
    iterations : int
        Newton iterations.
    contact : (n,) bool
        Vertices of a primitive pair closer than ``dhat`` at the end (the barrier holds them off their goals).
    min_distance : float
        Smallest distance between non-tolerated, non-adjacent primitives closer than ``dhat`` (length units;
        ``inf`` when none is).
    seconds : float
        Wall time.
    """

    X: np.ndarray
    converged: bool
    iterations: int
    contact: np.ndarray
    min_distance: float
    seconds: float


def tolerated_pair_keys(F, faces_to_edges, pairs, n, ne):
    """Keys of the tolerated primitive pairs: of each intersecting face pair, its 9 edge-edge and 6 face-vertex
    pairs whose primitives lie on intersecting faces only.

    A pair of two intersection sites is not among them (their faces do not intersect each other), nor one with a
    primitive next to the site (an edge or vertex shared with a face that does not intersect), so an intersection
    can neither reach another site nor spread to a clean face.

    Parameters
    ----------
    F : (m, 3) int
    faces_to_edges : (m, 3) int
        Row of the mesh's edges of each face's edges.
    pairs : (P, 2) int
        Face pairs (the reference's intersecting ones).
    n, ne : int
        Vertex and edge counts.

    Returns
    -------
    ee : (k,) int64
        Sorted keys ``min(a, b) ne + max(a, b)`` of the edge pairs ``(a, b)``.
    fv : (l,) int64
        Sorted keys ``f n + v`` of the face-vertex pairs ``(f, v)``.

    Examples
    --------
    >>> F = np.array([[0, 1, 2], [3, 4, 5]]); E2F = np.array([[0, 1, 2], [3, 4, 5]])
    >>> ee, fv = tolerated_pair_keys(F, E2F, np.array([[0, 1]]), 6, 6)
    >>> len(ee), fv.tolist()
    (9, [3, 4, 5, 6, 7, 8])
    """
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    faces = np.zeros(len(F), dtype=bool)
    faces[pairs.ravel()] = True
    vertex_ok = np.ones(n, dtype=bool)
    vertex_ok[F[~faces].ravel()] = False
    edge_ok = np.zeros(ne, dtype=bool)
    edge_ok[faces_to_edges[faces].ravel()] = True
    edge_ok[faces_to_edges[~faces].ravel()] = False
    f, g = pairs[:, 0], pairs[:, 1]
    a = np.repeat(faces_to_edges[f], 3, axis=1).ravel().astype(np.int64)
    b = np.tile(faces_to_edges[g], (1, 3)).ravel().astype(np.int64)
    ee = (np.minimum(a, b) * ne + np.maximum(a, b))[edge_ok[a] & edge_ok[b]]
    face, vertex = np.concatenate([np.repeat(f, 3), np.repeat(g, 3)]), np.concatenate([F[g].ravel(), F[f].ravel()])
    return np.unique(ee), np.unique((face * n + vertex)[vertex_ok[vertex]].astype(np.int64))


@dataclass(frozen=True)
class SweptCandidates:
    """The broad phase's candidates (:meth:`ContactSolver.candidates`) of the substep ``[a, b]`` (fractions of a move)
    of :meth:`ContactSolver.swept_step`: every pair that comes closer than ``dhat`` in it."""

    a: float
    b: float
    sets: list


class ContactSolver:
    """Moves poses of one reference toward goals through intersection-free shapes only.

    Parameters
    ----------
    V_ref : (n, 3) float
        Reference positions (the smoothness operator and the clearance are the reference's).
    F : (m, 3) int
    tolerated_pairs : (P, 2) int, optional
        Face pairs that may intersect (the reference's own intersecting pairs); none by default. Only their
        primitive pairs are dropped (:func:`tolerated_pair_keys`): two tolerated faces of different intersection
        sites cannot pass through each other. Primitive pairs closer than ``touching * d`` in the reference (parts
        touching at rest) are tolerated too.
    settings : ContactSettings
        ``ipctk`` runs on one thread: its parallel broad phase and barrier sums add up in an order that changes from
        run to run (lion-04's verify at 2 threads: two runs 1.7e-3 apart, 24 and 21 Newton iterations; at 1, equal).
        The Newton systems' factorizations take the BLAS threads of the caller (a stage's ``--threads``).

    Examples
    --------
    >>> from posefix.mesh.primitives import capsule
    >>> V, F = capsule(around=12, cap_rings=3, length_rings=6)
    >>> solver = ContactSolver(V, F)
    >>> r = solver.compute_pose(V, V + [0.5, 0.0, 0.0], np.ones(len(V)))
    >>> bool(r.converged), float(np.abs(r.X - V - [0.5, 0.0, 0.0]).max()) < 1e-12
    (True, True)
    """

    def __init__(self, V_ref, F, tolerated_pairs=None, settings=ContactSettings()):
        ipctk.set_num_threads(1)  # the same result for the same inputs (the class docstring)
        ipctk.set_logger_level(ipctk.LoggerLevel.warn)
        V_ref = np.asarray(V_ref, dtype=np.float64)
        self.F, self.d, self.settings = np.asarray(F, dtype=np.int32), bbox_diagonal(V_ref), settings
        E = ipctk.edges(self.F)
        self.edge_length = float(np.linalg.norm(V_ref[E[:, 0]] - V_ref[E[:, 1]], axis=1).mean())
        self.mesh = ipctk.CollisionMesh(V_ref, E, self.F)
        pairs = np.zeros((0, 2), np.int64) if tolerated_pairs is None else np.asarray(tolerated_pairs).reshape(-1, 2)
        self.tolerated = tolerated_pair_keys(self.F, self.mesh.faces_to_edges, pairs, len(V_ref), len(E))
        self.tolerated_faces = np.zeros(len(F), dtype=bool)
        self.tolerated_faces[pairs.ravel()] = True
        self._touching = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        self._touching = self._touching_pairs(V_ref)
        self._sub = self._tolerated_region(V_ref, E)
        self.clearance = self._clearance(V_ref)
        self.dhat = float(np.clip(0.5 * self.clearance, settings.dhat_min * self.d, settings.dhat * self.d))
        self.barrier = ipctk.BarrierPotential(self.dhat, 1.0)
        self._smoothness = _smoothness(V_ref, self.F, settings.smoothing * self.d)
        pattern = self._smoothness[1] + sp.identity(len(V_ref))
        order = fill_reducing_order(pattern)  # the 3 x 3 blocks' order from the vertices' (kids240: 20 min -> s)
        self._order = order, (3 * order[:, None] + np.arange(3)).ravel()
        self._system = (None, None)
        log.info("contact solver: %d vertices, %d tolerated face pairs and %d pairs touching at rest, clearance %.2e d, "
                 "dhat %.2e d", len(V_ref), len(pairs), sum(len(k) for k in self._touching),
                 self.clearance / self.d, self.dhat / self.d)

    def _touching_pairs(self, V):
        """(edge-pair keys, face-vertex keys) of the non-tolerated pairs closer than ``touching * d`` at ``V``: before
        the broad phase's filter is set. ipctk finds the contacts; only the candidates at their vertices are measured
        here (a few of the millions at 240k vertices)."""
        limit = self.settings.touching * self.d
        c = ipctk.Candidates()
        c.build(self.mesh, V, limit)
        contacts = ipctk.NormalCollisions()
        contacts.build(c, self.mesh, V, limit)
        if len(contacts) == 0:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        near = self.contact_vertices([contacts], len(V))
        (ee, ee_keys), (fv, fv_keys) = self._pairs(c)
        E, F = self.mesh.edges, self.mesh.faces
        keep_ee, keep_fv = self._kept(ee_keys, fv_keys)
        keep_ee &= near[E[ee]].any(axis=(1, 2))
        keep_fv &= near[F[fv[:, 0]]].any(axis=1) | near[fv[:, 1]]
        ee_c, fv_c = c.ee_candidates, c.fv_candidates  # (each read copies the whole list)
        ee_dist = np.sqrt([ee_c[i].compute_distance(V, E, F) for i in np.flatnonzero(keep_ee)])
        fv_dist = np.sqrt([fv_c[i].compute_distance(V, E, F) for i in np.flatnonzero(keep_fv)])
        return (np.unique(ee_keys[keep_ee][ee_dist < limit].astype(np.int64)),
                np.unique(fv_keys[keep_fv][fv_dist < limit].astype(np.int64)))

    def _clearance(self, V):
        """The reference's clearance, at most ``2 dhat d``: its smallest distance between non-tolerated, non-touching
        primitives. Looked for within radii doubling from ``2 dhat_min d`` (``self.dhat`` is the radius meanwhile):
        the closest pairs usually lie within the first (kids240: 51 s and 1.5 GB where one search up to ``2 dhat
        d`` took 9.5 min and 11 GB)."""
        largest, radius = 2.0 * self.settings.dhat * self.d, 2.0 * self.settings.dhat_min * self.d
        while True:
            self.dhat = min(radius, largest)
            distance = self.min_distance(V)
            if np.isfinite(distance) or self.dhat >= largest:
                return min(distance, largest)
            radius *= 2.0

    def _tolerated_region(self, V, E):
        """Set the broad phase's filter and return the tolerated region's own collision mesh (None if none).

        ipctk's vertex filter (``make_vertex_patches_filter``) drops every pair of primitives whose vertices all lie
        in the region (the tolerated faces' and touching pairs' vertices); :meth:`candidates` adds back those of them
        that are not tolerated, from the broad phase of the region's own mesh: ``(mesh, vertices (r,), edges (e_r,),
        faces (f_r,))``, the last three the region's primitives' ids in the whole mesh."""
        region = np.zeros(len(V), dtype=bool)
        region[self.F[self.tolerated_faces].ravel()] = True
        n, ne = len(V), len(E)
        touching_ee, touching_fv = self._touching
        region[E[np.concatenate([touching_ee // ne, touching_ee % ne])].ravel()] = True
        region[self.F[touching_fv // n].ravel()] = True
        region[touching_fv % n] = True
        if not region.any():
            return None
        self.mesh.can_collide = ipctk.make_vertex_patches_filter(np.where(region, 0, np.arange(1, n + 1)).astype(np.int32))
        vertices = np.flatnonzero(region)
        local = np.full(n, -1, dtype=np.int32)
        local[vertices] = np.arange(len(vertices))
        edges = np.flatnonzero(region[E].all(axis=1))
        faces = np.flatnonzero(region[self.F].all(axis=1))
        mesh = ipctk.CollisionMesh(V[vertices], local[E[edges]], local[self.F[faces]])
        return mesh, vertices, edges, faces

    def candidates(self, X0, X1=None, inflation=None):
        """The broad phase's primitive pairs near ``X0`` (or swept from ``X0`` to ``X1``), tolerated pairs removed.

        ipctk's default broad phase, its LBVH: on lion, cat and kids-0001 its hash grids and sweep and prune took
        3-10x its time for the same pairs (``benchmarks/broad_phase.py``, reports/bench/broad-phase.md).

        Parameters
        ----------
        X0, X1 : (n, 3) float
        inflation : float, optional
            Box inflation (length units); ``dhat / 2`` by default (every pair that comes closer than ``dhat``).

        Returns
        -------
        list of ipctk.Candidates
            The whole mesh's (ipctk's vertex filter applied), then, when there are any, the tolerated region's own
            pairs that are not tolerated, in the whole mesh's ids (a second, small set: merging it into the first
            would copy that one through Python).
        """
        X1 = X0 if X1 is None else X1
        inflation = 0.5 * self.dhat if inflation is None else inflation
        c = ipctk.Candidates()
        c.build(self.mesh, X0, X1, inflation)
        if self._sub is None:
            return [c]
        mesh, vertices, edges, faces = self._sub
        region = ipctk.Candidates()
        region.build(mesh, X0[vertices], X1[vertices], inflation)
        (ee, _), (fv, _) = self._pairs(region)
        ee, fv = edges[ee], np.column_stack([faces[fv[:, 0]], vertices[fv[:, 1]]])
        ee_keys, fv_keys = self._keys(ee, fv)
        keep_ee, keep_fv = self._kept(ee_keys, fv_keys)
        if not (keep_ee.any() or keep_fv.any()):
            return [c]
        extra = ipctk.Candidates()
        extra.ee_candidates = [ipctk.EdgeEdgeCandidate(int(a), int(b)) for a, b in ee[keep_ee]]
        extra.fv_candidates = [ipctk.FaceVertexCandidate(int(f), int(v)) for f, v in fv[keep_fv]]
        return [c, extra]

    def _kept(self, ee_keys, fv_keys):
        """Masks of the edge-edge pairs and face-vertex pairs (their keys (k,) and (l,), :meth:`_keys`) that are
        neither tolerated nor touching."""
        keep_ee = ~(np.isin(ee_keys, self.tolerated[0]) | np.isin(ee_keys, self._touching[0]))
        keep_fv = ~(np.isin(fv_keys, self.tolerated[1]) | np.isin(fv_keys, self._touching[1]))
        return keep_ee, keep_fv

    def _pairs(self, c):
        """((edge pairs (k, 2), keys (k,)), (face-vertex pairs (l, 2), keys (l,))) of the candidates ``c``, int64."""
        ee = np.array([(k.edge0_id, k.edge1_id) for k in c.ee_candidates], dtype=np.int64).reshape(-1, 2)
        fv = np.array([(k.face_id, k.vertex_id) for k in c.fv_candidates], dtype=np.int64).reshape(-1, 2)
        ee_keys, fv_keys = self._keys(ee, fv)
        return (ee, ee_keys), (fv, fv_keys)

    def _keys(self, ee, fv):
        """One int64 key per unordered edge pair of ``ee`` (k, 2) and per face-vertex pair of ``fv`` (l, 2)."""
        ne, n = self.mesh.num_edges, self.mesh.num_vertices
        return ee.min(axis=1) * ne + ee.max(axis=1), fv[:, 0] * n + fv[:, 1]

    def collisions(self, X, candidates=None, dhat=None):
        """The barrier's active pairs (closer than ``dhat``, the solver's by default) at ``X``, tolerated pairs
        excluded: a list of ipctk.NormalCollisions, one per set of :meth:`candidates`."""
        out = []
        for c in self.candidates(X) if candidates is None else candidates:
            C = ipctk.NormalCollisions()
            C.build(c, self.mesh, X, self.dhat if dhat is None else dhat)
            out.append(C)
        return out

    def min_distance(self, X, collisions=None):
        """Smallest distance between non-tolerated primitives closer than ``dhat`` at ``X``; ``inf`` when none is."""
        sets = self.collisions(X) if collisions is None else collisions
        return min((float(np.sqrt(C.compute_minimum_distance(self.mesh, X))) for C in sets if len(C)), default=np.inf)

    def collision_free_step(self, X0, X1):
        """Largest fraction in [0, 1] of the straight move ``X0`` -> ``X1`` (n, 3) that CCD proves intersection-free
        (non-tolerated pairs): :meth:`swept_step`'s."""
        return self.swept_step(X0, X1)[0]

    def swept_step(self, X0, X1):
        """``(alpha, swept)``: the largest fraction ``alpha`` in [0, 1] of the straight move ``X0`` -> ``X1`` (n, 3)
        that CCD proves intersection-free (non-tolerated pairs), and the :class:`SweptCandidates` of the substep where
        it stops: every pair closer than ``dhat`` anywhere in it, so the barrier's pairs at a point of it need no broad
        phase of their own (:meth:`collisions`; IPC's line search).

        The move is checked in equal substeps that each move no vertex farther than the reference's mean edge
        length, from the first, until one is cut: a primitive's swept box then overlaps its neighbours' only, where
        one box over the whole move overlaps all it passes (cat-04, a step of 7 edge lengths: 4.4 million candidate
        pairs and 0.86 s for one box, 0.23 million and 0.05 s in 8 substeps, the same step allowed)."""
        substeps = max(1, int(np.ceil(np.linalg.norm(X1 - X0, axis=1).max() / self.edge_length)))
        for k in range(substeps):
            a, b = k / substeps, (k + 1) / substeps
            Xa, Xb = X0 + a * (X1 - X0), (X1 if k == substeps - 1 else X0 + b * (X1 - X0))
            sets = self.candidates(Xa, Xb)
            step = min((c.compute_collision_free_stepsize(self.mesh, Xa, Xb, 0.0, _CCD) for c in sets if not c.empty()),
                       default=1.0)
            if step < 1.0 or k == substeps - 1:
                return (a + step * (b - a) if step < 1.0 else 1.0), SweptCandidates(a, b, sets)

    def blocked_vertices(self, X0, X1, among=None):
        """Vertices of the pairs that collide along the straight move ``X0`` -> ``X1`` (n, 3), (n,) bool: the moving
        vertices of every non-tolerated pair with a vertex in ``among`` ((n,) bool; the moving vertices by default)
        whose CCD finds an impact. Holding them back, then those of the pairs with a vertex held back, and so on,
        leaves a move CCD allows.

        Examples
        --------
        >>> T = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0]])
        >>> V = np.vstack([T, 0.1 * T + [.2, .2, .5], T + 3])  # a triangle, a small one above it, one far away
        >>> solver = ContactSolver(V, np.arange(9).reshape(3, 3))
        >>> X1 = V + np.repeat([[0, 0, 0], [0, 0, -1], [0, 0, 1]], 3, axis=0)  # the small one down through the first
        >>> np.flatnonzero(solver.blocked_vertices(V, X1)).tolist()
        [3, 4, 5]
        """
        moving = (X0 != X1).any(axis=1)
        blocked = np.zeros(len(X0), dtype=bool)
        with self._moving(moving if among is None else among):
            sets = self.candidates(X0, X1)
        reach = np.linalg.norm(X1 - X0, axis=1)
        for c in sets:
            (ee, _), (fv, _) = self._pairs(c)
            edges, faces = self.mesh.edges[ee].reshape(-1, 4), self.mesh.faces[fv[:, 0]]
            for ids, split, ccd in ((edges, 2, _CCD.edge_edge_ccd),
                                    (np.column_stack([fv[:, 1], faces]), 1, _CCD.point_triangle_ccd)):
                # a pair closes by at most its vertices' moves; Additive CCD reports a pair that closes by 0.9 of
                # its distance, which is at least its primitives' boxes' (most pairs are left out here)
                ids = ids[_box_distance(X0, ids, split) <= 2.0 * reach[ids].sum(axis=1)]
                for k in ids:
                    if ccd(*X0[k], *X1[k], 0.0, 1.0)[0]:
                        blocked[k] = True
        return blocked & moving

    def keep_gap(self, X, movable):
        """``X`` with every non-tolerated pair that has a ``movable`` vertex at least :func:`float32_gap` apart.

        A pose written as float32 (USD ``point3f``, glTF) is rounded: two primitives closer than the rounding
        could end up intersecting in the file. The vertices of the pairs closer than the gap move, up to
        :data:`GAP_STEPS` times, by the gap along the descent of a barrier whose activation distance is twice the
        gap, each push bounded by CCD (a few float32 spacings: the shape does not change).

        Parameters
        ----------
        X : (n, 3) float
            Intersection-free positions (up to the tolerated faces).
        movable : (n,) bool
            Vertices that may move (e.g. not the constrained vertices exactly on their targets).

        Returns
        -------
        X : (n, 3) float
        distance : float
            The smallest distance left between non-tolerated primitives closer than twice the gap (``inf`` if
            none); below the gap only where no vertex of the pair is ``movable``.
        """
        gap = float32_gap(X)
        barrier, pushes = ipctk.BarrierPotential(2.0 * gap, 1.0), 0
        for pushes in range(GAP_STEPS + 1):
            close = [C for C in self.collisions(X, self.candidates(X, inflation=gap), 2.0 * gap) if len(C)]
            distance = min((np.sqrt(C.compute_minimum_distance(self.mesh, X)) for C in close), default=np.inf)
            g = sum((barrier.gradient(C, self.mesh, X) for C in close), np.zeros(X.size)).reshape(-1, 3)
            g[~np.asarray(movable, dtype=bool)] = 0.0
            norm = np.linalg.norm(g, axis=1)
            if distance >= gap or not norm.any() or pushes == GAP_STEPS:
                break
            push = -gap * g / np.maximum(norm, TINY)[:, None]
            X = X + self.collision_free_step(X, X + push) * push
        if pushes:
            log.info("contact solver: %d pushes toward a gap of %.1e d (float32 rounding), %.1e d left", pushes,
                     gap / self.d, distance / self.d)
        return X, float(distance)

    def contact_vertices(self, collisions, n):
        """Vertices of the pairs of ``collisions`` (a list of ipctk.NormalCollisions), (n,) bool."""
        contact = np.zeros(n, dtype=bool)
        for C in collisions:
            for k in range(len(C)):
                ids = np.asarray(C[k].vertex_ids(self.mesh.edges, self.mesh.faces))
                contact[ids[ids >= 0]] = True
        return contact

    def barrier_terms(self, collisions, X, order=0):
        """The barrier's value (``order`` 0, float), gradient (1, (3n,)) or PSD-projected Hessian (2, sparse
        (3n, 3n)) at ``X`` over ``collisions`` (a list of ipctk.NormalCollisions)."""
        sets = [C for C in collisions if len(C)]
        if order == 0:
            return float(sum(self.barrier(C, self.mesh, X) for C in sets))
        if order == 1:
            return sum((self.barrier.gradient(C, self.mesh, X) for C in sets), np.zeros(X.size))
        return sum((self.barrier.hessian(C, self.mesh, X, _PSD) for C in sets), sp.csc_matrix((X.size, X.size)))

    def compute_pose(self, start, goal, weights, tolerance=None, shape=None, max_iterations=None):
        """Move ``start`` toward ``goal`` without leaving the intersection-free set.

        Parameters
        ----------
        start : (n, 3) float
            Intersection-free positions (up to the tolerated faces): every non-tolerated pair apart.
        goal : (n, 3) float
            Goal positions.
        weights : (n,) float
            Per-vertex weights of the goals (positive somewhere on every connected part).
        tolerance : float, optional
            Newton's stopping step / d (``settings.tolerance`` by default; looser for waypoints of a path).
        shape : (n, 3) float, optional
            The shape the smoothness term keeps: it smooths the displacement from ``shape`` instead of from
            ``goal`` (``goal`` by default), so the result follows ``goal`` above the smoothing length and
            ``shape``'s details below it.
        max_iterations : int, optional
            Newton iterations at most (``settings.max_iterations`` by default).

        Returns
        -------
        ContactResult

        Raises
        ------
        ValueError
            ``start`` has two non-tolerated primitives in contact (distance 0): it is not intersection-free.
        """
        t0 = time.perf_counter()
        newton = _GoalNewton(self, np.asarray(goal, dtype=np.float64), np.asarray(weights, dtype=np.float64),
                             self.settings.tolerance if tolerance is None else tolerance)
        if shape is not None:  # 1/2 |x - g|_W^2 + 1/2 |x - s|_S^2 = 1/2 |x - Q^-1 (W g + S s)|_Q^2 + const
            mass, smooth = self._smoothness
            newton.goal = newton.system.solve_q((weights * mass)[:, None] * newton.goal + smooth @ shape)
        X, converged, iterations = newton.run(np.array(start, dtype=np.float64), max_iterations)
        C = self.collisions(X)
        return ContactResult(X, converged, iterations, self.contact_vertices(C, len(X)), self.min_distance(X, C),
                             time.perf_counter() - t0)

    def compute_elastic(self, start, goal, weights, elastic, pinned=None, max_iterations=None):
        """Move ``start`` toward ``goal`` under an elastic energy without leaving the intersection-free set.

        Minimizes ``1/2 sum_i w_i a_i |x_i - g_i|^2 + 1/2 l^2 r(x) . r(x) + kappa B(x)`` over the vertices not
        ``pinned`` (they stay where ``start`` has them): ``r`` the residuals of ``elastic`` (dimensionless: the
        discrete shell's stretching and bending, face areas), ``l`` the reference's mean edge length, ``a`` vertex
        areas over their mean. The elastic energy is invariant to rigid motion, so a part that turns keeps its shape;
        the goal term pulls the whole toward ``goal``. Projected Newton: Gauss-Newton's Hessian ``l^2 J^T J`` of the
        elastic terms and the barrier's PSD-projected one, factorized at every step; every step bounded by CCD.

        Parameters
        ----------
        start : (n, 3) float
            Intersection-free positions (see :meth:`compute_pose`).
        goal : (n, 3) float
        weights : (n,) float
            Per-vertex weights of the goals (the free region's small: the elastic energy keeps its shape).
        elastic : posefix.mesh.shells.ElasticEnergy
            Residuals and their Jacobian with a rest state (:func:`posefix.mesh.shells.rest_elastic_energy`).
        pinned : (n,) bool, optional
            Vertices that do not move (none by default). Not unknowns: the energy's terms and the barrier's pairs
            among them alone are constant and left out of every step (:meth:`_moving`,
            :meth:`posefix.mesh.shells.ElasticEnergy.restricted`).
        max_iterations : int, optional
            Newton iterations at most (``settings.max_iterations`` by default).

        Returns
        -------
        ContactResult
        """
        t0 = time.perf_counter()
        pinned = np.zeros(len(start), dtype=bool) if pinned is None else np.asarray(pinned, dtype=bool)
        newton = _ElasticNewton(self, np.asarray(goal, dtype=np.float64), np.asarray(weights, dtype=np.float64),
                                elastic.restricted(~pinned) if pinned.any() else elastic, pinned,
                                self.settings.tolerance)
        with self._moving(~pinned):
            X, converged, iterations = newton.run(np.array(start, dtype=np.float64), max_iterations)
        C = self.collisions(X)
        return ContactResult(X, converged, iterations, self.contact_vertices(C, len(X)), self.min_distance(X, C),
                             time.perf_counter() - t0)

    @contextmanager
    def _moving(self, moving):
        """Within: the broad phase keeps only the pairs with a vertex in ``moving`` ((n,) bool): the others keep
        their distance, so their barrier is a constant and no step can close them (kids-0001: 48k of 60k
        vertices pinned)."""
        whole = self.mesh.can_collide
        if not moving.all():
            patches = np.where(moving, np.arange(1, len(moving) + 1), 0).astype(np.int32)
            self.mesh.can_collide = whole & ipctk.make_vertex_patches_filter(patches)
        try:
            yield
        finally:
            self.mesh.can_collide = whole

    def elastic_energy(self, X, goal, weights, elastic, groups=None):
        """The energy :meth:`compute_elastic` minimizes, less the barrier, at ``X`` (n, 3): float (length^2), or
        with ``groups`` ((n,) int, -1 for none) its share of each group, (groups.max() + 1,) float: a vertex's goal
        term and every residual of a group's vertex (the largest group among its vertices)."""
        newton = _ElasticNewton(self, np.asarray(goal, dtype=np.float64), np.asarray(weights, dtype=np.float64),
                                elastic, np.zeros(len(X), dtype=bool), self.settings.tolerance)
        if groups is None:
            return newton.energy(X)
        r, J = elastic.residuals(X), sp.coo_matrix(elastic.jacobian(X))
        row_group = np.full(len(r), -1)
        np.maximum.at(row_group, J.row, groups[J.col // 3])
        out = np.zeros(groups.max() + 1)
        rows, vertices = row_group >= 0, groups >= 0
        np.add.at(out, row_group[rows], 0.5 * newton.scale * r[rows] ** 2)
        pull = 0.5 * newton.goal_weights * ((X - newton.goal) ** 2).sum(axis=1)
        np.add.at(out, groups[vertices], pull[vertices])
        return out

    def compute_path(self, start, waypoints, tolerance=None, weights=None, max_iterations=None):
        """Carry ``start`` through ``waypoints`` in turn, each from where the last one stopped.

        Parameters
        ----------
        start : (n, 3) float
            Intersection-free positions (see :meth:`compute_pose`).
        waypoints : (K, n, 3) float
            The poses to follow, K >= 1; all but the last are solved to :data:`WAYPOINT_TOLERANCE` only.
        tolerance : float, optional
            Newton's stopping step / d on the last waypoint (``settings.tolerance`` by default).
        weights : (n,) float, optional
            Per-vertex weights of the waypoints (uniform by default).
        max_iterations : int, optional
            Newton iterations at most per waypoint (``settings.max_iterations`` by default).

        Returns
        -------
        ContactResult
            At the last waypoint; ``iterations`` and ``seconds`` of the whole path, ``converged`` of every step.
        """
        X = np.asarray(start, dtype=np.float64)
        weights = np.ones(len(start)) if weights is None else np.asarray(weights, dtype=np.float64)
        iterations, converged, seconds = 0, True, 0.0
        for k, goal in enumerate(waypoints):
            last = k == len(waypoints) - 1
            result = self.compute_pose(X, goal, weights, tolerance if last else WAYPOINT_TOLERANCE,
                                       max_iterations=max_iterations)
            X, iterations, seconds = result.X, iterations + result.iterations, seconds + result.seconds
            converged &= result.converged
            log.debug("waypoint %d of %d: %d Newton iterations", k + 1, len(waypoints), result.iterations)
        result.iterations, result.converged, result.seconds = iterations, converged, seconds
        return result


def _box_distance(X, stencils, split):
    """Distance between the bounding boxes of each stencil's two primitives at ``X`` (n, 3), (k,) float: the
    stencils (k, 4) vertex ids, the first primitive's ``split`` of them (edge-edge 2, point-triangle 1)."""
    P, Q = X[stencils[:, :split]], X[stencils[:, split:]]
    gap = np.maximum(P.min(axis=1) - Q.max(axis=1), Q.min(axis=1) - P.max(axis=1))
    return np.linalg.norm(np.maximum(gap, 0.0), axis=1)


def _smoothness(V, F, length):
    """Vertex areas over their mean (n,) and the smoothness matrix ``l^4 L^T M^-1 L / mean area`` (n, n)."""
    area = vertex_areas(V, F)
    mean = float(area.mean())
    L = cotangent_laplacian(V, F)
    return area / mean, (L.T @ sp.diags(1.0 / area) @ L) * (length ** 4 / mean)


_SCHUR_VERTICES = 1000
"""Most vertices in contact for which a Newton step solves the Schur complement of their unknowns (dense,
3m x 3m) with the cached columns of ``Q^-1``; with more, the whole Hessian is factorized."""
_SCHUR_BYTES = 1e9
"""Most bytes of cached columns of ``Q^-1`` (n floats each: 2,000 columns at 60k vertices); when full, the cache
starts again, and a step with more vertices in contact than fit factorizes the whole Hessian."""


class _NewtonSystem:
    """Newton steps ``(H0 + Hb) dx = r`` of one set of goal weights, ``H0 = Q (x) I_3`` (goals and smoothness).

    ``Q`` (n x n) is factorized once; the barrier's Hessian ``Hb`` lives on the m vertices in contact, so a step
    is one solve with ``Q`` and a dense solve of the 3m contact unknowns' Schur complement, ``(I + S Hb_c) y = P
    H0^-1 r`` with ``S = P H0^-1 P^T``, and ``dx = H0^-1 r - H0^-1 P^T Hb_c y``. The columns of ``Q^-1`` at the
    contact vertices are cached (at most ``_SCHUR_BYTES``): the contacts change little from one step to the next.
    """

    def __init__(self, Q, orders):
        self.Q, self.orders = sp.csc_matrix(Q), orders
        self.H0 = sp.kron(self.Q, sp.identity(3), format="csr")  # once (kids: kron + add 3.9 s, the add 0.014 s)
        p = orders[0]
        self.lu = factorized(self.Q[p][:, p], "NATURAL", symmetric=True)
        self.W, self.count, self.column = np.zeros((0, Q.shape[0])), 0, np.full(Q.shape[0], -1)
        self.capacity = max(1, int(_SCHUR_BYTES // (8 * Q.shape[0])))

    def solve_q(self, R):
        """``Q^-1 R`` for ``R`` (n, k)."""
        p, out = self.orders[0], np.empty_like(R)
        out[p] = self.lu.solve(np.ascontiguousarray(R[p]))
        return out

    def inverse_columns(self, vertices):
        """Where the columns of ``Q^-1`` at ``vertices`` (m,) are stored, as rows of ``self.W`` (k, n), (m,) int:
        each is computed once, into a buffer that doubles when full, up to ``self.capacity`` (then it starts
        again)."""
        missing = vertices[self.column[vertices] < 0]
        if self.count + len(missing) > self.capacity:
            self.column[:], self.count, missing = -1, 0, vertices
        if len(missing):
            if self.count + len(missing) > len(self.W):
                size = min(self.capacity, max(2 * len(self.W), self.count + len(missing)))
                W = np.zeros((size, self.Q.shape[0]))
                W[:self.count] = self.W[:self.count]
                self.W = W
            E = np.zeros((self.Q.shape[0], len(missing)))
            E[missing, np.arange(len(missing))] = 1.0
            self.column[missing] = self.count + np.arange(len(missing))
            self.W[self.count:self.count + len(missing)] = self.solve_q(E).T
            self.count += len(missing)
        return self.column[vertices]

    def solve(self, R, Hb):
        """The step ``(H0 + Hb)^-1 r`` for ``r`` as ``R`` (n, 3) and ``Hb`` sparse (3n, 3n) or 0, (n, 3)."""
        X0 = self.solve_q(R)
        if not sp.issparse(Hb) or Hb.nnz == 0:
            return X0
        Hb = sp.csr_matrix(Hb)
        vertices = np.unique(np.flatnonzero(np.diff(Hb.indptr)) // 3)
        if len(vertices) > min(_SCHUR_VERTICES, self.capacity):
            return self._direct(R, Hb)
        dofs = (3 * vertices[:, None] + np.arange(3)).ravel()
        B = sp.csc_matrix(Hb[dofs][:, dofs])  # symmetric
        columns = self.inverse_columns(vertices)  # (before self.W is read: it may grow)
        W = self.W[columns]  # (m, n): Q^-1 at the contact vertices
        Wc = W[:, vertices]  # S = Wc (x) I_3 (symmetric): (S B)^T = B S, whose column 3i+a is B[:, a::3] @ Wc[:, i]
        BS = np.empty((len(dofs), len(dofs)))  # (no 3m x 3m Kronecker product formed)
        for a in range(3):
            BS[:, a::3] = B[:, a::3] @ Wc
        M = BS.T
        M[np.diag_indices_from(M)] += 1.0
        y = scipy.linalg.solve(M, X0[vertices].ravel(), overwrite_a=True, check_finite=False)
        return X0 - W.T @ (B @ y).reshape(-1, 3)

    def _direct(self, R, Hb):
        """The step with the whole Hessian factorized (CHOLMOD when installed: kids240 ~2.5 min and 8 GB with SuperLU
        per step), (n, 3)."""
        H = self.H0 + Hb
        return cholesky_factorized(H, self.orders[1]).solve(R.ravel()).reshape(-1, 3)


class _Newton:
    """Newton's method with the barrier and a CCD-bounded backtracking line search for one pose; the energy
    without the barrier (:meth:`energy`, its gradient and Hessian) is a subclass's."""

    def __init__(self, solver, goal, tolerance):
        self.s, self.goal, self.tolerance = solver, goal, tolerance
        self.kappa = None
        self.kappa_max = None

    def run(self, X, max_iterations=None):
        s = self.s
        most = s.settings.max_iterations if max_iterations is None else max_iterations
        C = s.collisions(X)
        if s.min_distance(X, C) <= 0.0:
            raise ValueError("the start has non-tolerated primitives in contact (it is not intersection-free)")
        self._init_stiffness(X, C)
        previous = s.min_distance(X, C)
        for it in range(1, most + 1):
            dx = self._direction(X, C)
            X_new, C_new, ok = self._line_search(X, dx, C)
            if not ok:
                return X, np.abs(dx).max() <= self.tolerance * s.d, it
            log.debug("newton %d: step %.2e d (Newton's %.2e d), %d active pairs, kappa %.2e", it,
                      np.abs(X_new - X).max() / s.d, np.abs(dx).max() / s.d, sum(map(len, C_new)), self.kappa)
            X, C = X_new, C_new
            if np.abs(dx).max() <= self.tolerance * s.d:
                return X, True, it
            current = s.min_distance(X, C)
            if np.isfinite(current):
                self.kappa = ipctk.update_barrier_stiffness(previous ** 2 if np.isfinite(previous) else s.dhat ** 2,
                                                            current ** 2, self.kappa_max, self.kappa, s.d)
            previous = current
        return X, False, most

    def _init_stiffness(self, X, C):
        """IPC's initial barrier stiffness and its cap, from the gradients at ``X`` and :meth:`_mass`."""
        s = self.s
        self.kappa, self.kappa_max = ipctk.initial_barrier_stiffness(
            s.d, s.barrier.barrier, s.dhat, self._mass(), self.gradient(X), self._unknowns(s.barrier_terms(C, X, 1)))

    def _unknowns(self, g):
        """A gradient (3n,) with the entries of the vertices that do not move zeroed (none here)."""
        return g

    def _line_search(self, X, dx, C):
        """``(X, collisions, accepted)`` after the largest step ``alpha dx`` that CCD allows and that lowers the
        energy, halving from there.

        The trial points' barrier pairs (IPC's line search: the step is intersection-free, the pairs closer than
        ``dhat`` at its end are those the barrier sees) come from the candidates CCD swept where the trial point lies
        in the substep that stopped it (the first trial always), else from a broad phase at it (kids-0001's contact
        repair: 191 trial points, 38 of its 370 s; from the swept candidates 0.14 s each instead of 0.25 s)."""
        s = self.s
        alpha, swept = s.swept_step(X, X + dx)
        e0 = self.energy(X) + self.kappa * s.barrier_terms(C, X)
        while alpha > ROUNDOFF:
            X_new = X + alpha * dx
            C_new = s.collisions(X_new, swept.sets if swept.a <= alpha <= swept.b else None)
            if self.energy(X_new) + self.kappa * s.barrier_terms(C_new, X_new) <= e0:
                return X_new, C_new, True
            alpha *= 0.5
        return X, C, False


class _GoalNewton(_Newton):
    """The quadratic goal and smoothness energy ``1/2 (x - g)^T H0 (x - g)`` (module docstring)."""

    def __init__(self, solver, goal, weights, tolerance):
        super().__init__(solver, goal, tolerance)
        key = weights.tobytes()
        if solver._system[0] != key:  # the factorization of Q serves every pose with the same weights
            mass, smooth = solver._smoothness
            solver._system = key, _NewtonSystem(sp.diags(weights * mass) + smooth, solver._order)
        self.system = solver._system[1]
        self.H0 = self.system.H0

    def energy(self, X):
        u = (X - self.goal).ravel()
        return 0.5 * u @ (self.H0 @ u)

    def gradient(self, X):
        return self.H0 @ (X - self.goal).ravel()

    def _mass(self):
        """IPC's "average mass", taken as the smallest diagonal entry of the goal term's Hessian with unit weights:
        V_C's weight is a penalty, not a mass, and the mean (dominated by it and by the smoothness of fine regions)
        made the barrier so stiff that CCD cut almost every step (lion-04: 175 Newton iterations against 63)."""
        mass, smooth = self.s._smoothness
        return float((mass + smooth.diagonal()).min())

    def _direction(self, X, C):
        s = self.s
        grad = self.gradient(X) + self.kappa * s.barrier_terms(C, X, 1)
        return self.system.solve(-grad.reshape(-1, 3), self.kappa * s.barrier_terms(C, X, 2))


class _ElasticNewton(_Newton):
    """The elastic energy ``1/2 sum_i w_i a_i |x_i - g_i|^2 + 1/2 l^2 r(x) . r(x)`` (:meth:`ContactSolver.compute_elastic`)
    over the vertices not ``pinned``; its Hessian, Gauss-Newton's ``l^2 J^T J`` for the elastic terms (PSD), is
    factorized at every step."""

    def __init__(self, solver, goal, weights, elastic, pinned, tolerance):
        super().__init__(solver, goal, tolerance)
        self.elastic, self.scale = elastic, solver.edge_length ** 2
        self.goal_weights = weights * solver._smoothness[0]
        self.dofs = (3 * np.flatnonzero(~pinned)[:, None] + np.arange(3)).ravel()

    def energy(self, X):
        r = self.elastic.residuals(X)
        return 0.5 * float(self.goal_weights @ ((X - self.goal) ** 2).sum(axis=1)) + 0.5 * self.scale * float(r @ r)

    def gradient(self, X):
        """The energy's gradient, (3n,), zero at the pinned vertices."""
        grad = (self.goal_weights[:, None] * (X - self.goal)).ravel()
        grad += self.scale * (self.elastic.jacobian(X).T @ self.elastic.residuals(X))
        return self._unknowns(grad)

    def _unknowns(self, g):
        out = np.zeros_like(g)
        out[self.dofs] = g[self.dofs]
        return out

    def _mass(self):
        """IPC's "average mass": the median diagonal entry of the energy's Hessian at the goal over the free unknowns,
        with the lightest goal weight everywhere (V_C's weight is a penalty, not a mass: with it the barrier was
        stiffer by 1e4 and the steps a thousandth of Newton's)."""
        J = sp.csc_matrix(self.elastic.jacobian(self.goal))[:, self.dofs]
        lightest = np.repeat(self.goal_weights.min() * np.ones(len(self.goal)), 3)[self.dofs]
        return float(np.median(lightest + self.scale * np.asarray(J.multiply(J).sum(axis=0)).ravel()))

    def _hessian(self, X):
        J = sp.csc_matrix(self.elastic.jacobian(X))[:, self.dofs]
        weights = np.repeat(self.goal_weights, 3)[self.dofs]
        return sp.diags(weights) + self.scale * (J.T @ J)

    def _direction(self, X, C):
        s = self.s
        grad = self.gradient(X) + self.kappa * s.barrier_terms(C, X, 1)
        H = self._hessian(X)
        Hb = s.barrier_terms(C, X, 2)
        if sp.issparse(Hb) and Hb.nnz:
            H = H + self.kappa * sp.csr_matrix(Hb)[self.dofs][:, self.dofs]
        dx = np.zeros(X.size)
        dx[self.dofs] = _spd_solve(H, -grad[self.dofs])
        return dx.reshape(-1, 3)


def _spd_solve(H, b):
    """``H^-1 b`` for the PSD Newton matrix ``H`` (sparse (k, k), positive diagonal), by Cholesky. Where rounding
    makes it numerically indefinite (the barrier's PSD-projected Hessian times a stiffness of 1e12 beside goal
    weights of 1e-6: cat-09), its diagonal is scaled by ``1 + tau``, ``tau`` from ``ROUNDOFF`` tenfold until it
    factorizes (each unknown damped relative to its own curvature, as Levenberg-Marquardt's scaled damping)."""
    try:
        return cholesky_factorized(H).solve(b)
    except np.linalg.LinAlgError:
        tau, D = ROUNDOFF, sp.diags(H.diagonal())
        while True:
            try:
                x = cholesky_factorized(H + tau * D).solve(b)
                log.debug("Newton matrix's diagonal scaled by 1 + %.0e to factorize", tau)
                return x
            except np.linalg.LinAlgError:
                tau *= 10.0
