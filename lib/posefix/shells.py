"""Discrete-shell energy of example-driven deformation (Fröhlich & Botsch 2011) and its Gauss–Newton solver.

S0 §5 ("Benefits for subsequent processing") checks repaired poses by how a downstream nonlinear
solver behaves on them. The energy is a sum of squared residuals, one per edge for stretching and
one per interior edge for bending:

    r_l = w_l (l_e - l*_e),          w_l = sqrt(k_l / lbar_e^2)
    r_b = w_b wrap(theta_e - theta*_e), w_b = sqrt(k_b lbar_e^2 / (A_1 + A_2))

with l the edge length, theta the signed dihedral angle, lbar, A_1, A_2 the reference edge length
and the areas of the edge's two triangles, and example-driven targets
l* = l0 + alpha (l_pose - l0), theta* = theta0 + alpha wrap(theta_pose - theta0).

Dihedral angle convention: for an interior edge (i, j) whose first face is (i, j, k) and second
(j, i, l) (both counter-clockwise), theta = atan2(e_hat . (n1 x n2), n1 . n2) in (-pi, pi], with
n1, n2 the faces' normals and e_hat = (x_j - x_i) / |x_j - x_i|: 0 when flat, positive when the
surface bends away from its normals (convex), +-pi when folded onto itself. Differences of angles
are wrapped to (-pi, pi] (``wrap_angle``), so a fold through +-pi costs its true angle, not 2 pi.
"""

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator, cg, splu

from posefix.geometry import edge_lengths, face_areas
from posefix.topology import edges

STOP_REASONS = ("converged", "stall", "max_iters", "line-search failure", "collapsed triangle")
EXAMPLES = ("original", "repaired")
"""The two examples of the downstream check (S0 §5), in the order of downstream.h5's ``example`` codes."""


def wrap_angle(a):
    """Angles (radians, any shape) mapped to (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(a, dtype=float), 2.0 * np.pi)


@dataclass
class Hinges:
    """Edges of a triangle mesh with their stencils.

    Attributes
    ----------
    edges : (e, 2) int64
        Every undirected edge (stretching terms).
    hinges : (h, 4) int64
        Interior edges with exactly two faces as ``(i, j, k, l)``: faces ``(i, j, k)`` and
        ``(j, i, l)`` in their own orientation (bending terms).
    hinge_faces : (h, 2) int64
        The two faces of every hinge.
    """
    edges: np.ndarray
    hinges: np.ndarray
    hinge_faces: np.ndarray


def mesh_hinges(F):
    """Edges and bending hinges of a triangle mesh, (m, 3) int faces -> :class:`Hinges`.

    Boundary edges and edges of three or more faces get no bending term.
    """
    F = np.asarray(F, dtype=np.int64)
    m = len(F)
    a = F.reshape(-1)                      # directed half-edge a -> b of face f, opposite vertex c
    b = F[:, [1, 2, 0]].reshape(-1)
    c = F[:, [2, 0, 1]].reshape(-1)
    f = np.repeat(np.arange(m), 3)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    order = np.lexsort((f, hi, lo))
    lo, hi = lo[order], hi[order]
    starts = np.flatnonzero(np.r_[True, (lo[1:] != lo[:-1]) | (hi[1:] != hi[:-1])])
    counts = np.diff(np.r_[starts, len(lo)])
    first = order[starts[counts == 2]]
    second = order[starts[counts == 2] + 1]
    keep = a[first] == b[second]           # consistently oriented pair: (i, j, k) and (j, i, l)
    first, second = first[keep], second[keep]
    hinges = np.stack([a[first], b[first], c[first], c[second]], axis=1)
    return Hinges(edges(F), hinges, np.stack([f[first], f[second]], axis=1))


def dihedral_angles(V, H):
    """Signed dihedral angles of hinges ``H`` (h, 4) int (module convention), (h,) float in (-pi, pi]."""
    xi, xj, xk, xl = (V[H[:, c]] for c in range(4))
    e = xj - xi
    n1 = np.cross(e, xk - xi)
    n2 = np.cross(xi - xj, xl - xj)
    e_hat = e / np.maximum(np.linalg.norm(e, axis=1), 1e-300)[:, None]
    return np.arctan2(np.einsum("ij,ij->i", np.cross(n1, n2), e_hat), np.einsum("ij,ij->i", n1, n2))


def dihedral_gradients(V, H):
    """Gradients of the dihedral angles with respect to the hinge's four vertices.

    Returns
    -------
    (h, 4, 3) float
        d theta / d x for x_i, x_j, x_k, x_l (Bridson et al. 2003); they sum to zero. Infinite
        for a zero-area face (the gradient grows like 1 / area).
    """
    xi, xj, xk, xl = (V[H[:, c]] for c in range(4))
    e = xj - xi
    le = np.linalg.norm(e, axis=1)
    n1 = np.cross(e, xk - xi)
    n2 = np.cross(xi - xj, xl - xj)
    with np.errstate(divide="ignore", invalid="ignore"):
        u1 = n1 / np.einsum("ij,ij->i", n1, n1)[:, None]
        u2 = n2 / np.einsum("ij,ij->i", n2, n2)[:, None]
        gk = -le[:, None] * u1
        gl = -le[:, None] * u2
        tk = np.einsum("ij,ij->i", xk - xj, e) / le
        tl = np.einsum("ij,ij->i", xl - xj, e) / le
        sk = np.einsum("ij,ij->i", xk - xi, e) / le
        sl = np.einsum("ij,ij->i", xl - xi, e) / le
        gi = -(tk[:, None] * u1 + tl[:, None] * u2)
        gj = sk[:, None] * u1 + sl[:, None] * u2
    return np.stack([gi, gj, gk, gl], axis=1)


@dataclass
class ShellEnergy:
    """The example-driven discrete-shell energy of one mesh and one example.

    Build with :func:`shell_energy`. ``residuals(V)`` gives r (e + h,), ``jacobian(V)`` the sparse
    d r / d vec(V) ((e + h, 3 n) CSR, column ``3 v + c`` for coordinate c of vertex v); the energy is
    ``r . r`` (dimensionless).
    """
    hinges: Hinges
    w_stretch: np.ndarray      # (e,) w_l
    w_bend: np.ndarray         # (h,) w_b
    length_target: np.ndarray  # (e,) l*
    angle_target: np.ndarray   # (h,) theta*
    n: int
    _rows: np.ndarray = field(repr=False, default=None)
    _cols: np.ndarray = field(repr=False, default=None)

    def __post_init__(self):
        E, H = self.hinges.edges, self.hinges.hinges
        e, h = len(E), len(H)
        rows_l = np.repeat(np.arange(e), 6)
        cols_l = (3 * E[:, [0, 0, 0, 1, 1, 1]] + np.tile([0, 1, 2], 2)).reshape(-1)
        rows_b = np.repeat(e + np.arange(h), 12)
        cols_b = (3 * np.repeat(H, 3, axis=1) + np.tile([0, 1, 2], 4)).reshape(-1)
        self._rows = np.r_[rows_l, rows_b]
        self._cols = np.r_[cols_l, cols_b]

    def residuals(self, V):
        """Residuals r, (e + h,) float: stretching rows first, then bending rows."""
        rl = self.w_stretch * (edge_lengths(V, self.hinges.edges) - self.length_target)
        rb = self.w_bend * wrap_angle(dihedral_angles(V, self.hinges.hinges) - self.angle_target)
        return np.r_[rl, rb]

    def jacobian_values(self, V):
        """Entries of the Jacobian in the fixed pattern (``jacobian`` builds the matrix from them)."""
        E = self.hinges.edges
        d = V[E[:, 1]] - V[E[:, 0]]
        u = d / np.maximum(np.linalg.norm(d, axis=1), 1e-300)[:, None]
        gl = self.w_stretch[:, None] * np.c_[-u, u]
        gb = self.w_bend[:, None] * dihedral_gradients(V, self.hinges.hinges).reshape(len(self.w_bend), 12)
        return np.r_[gl.reshape(-1), gb.reshape(-1)]

    def jacobian(self, V):
        """Sparse Jacobian d r / d vec(V), (e + h, 3 n) CSR."""
        shape = (len(self.w_stretch) + len(self.w_bend), 3 * self.n)
        return sp.csr_matrix((self.jacobian_values(V), (self._rows, self._cols)), shape=shape)

    def energy(self, V):
        """Energy sum r^2 at ``V`` (n, 3) float (dimensionless)."""
        r = self.residuals(V)
        return float(r @ r)


def shell_energy(V_ref, F, V_example, alpha, k_stretch=1.0, k_bend=1e-2, hinges=None):
    """Example-driven shell energy: deform ``V_ref`` towards ``alpha`` of the way to ``V_example``.

    Parameters
    ----------
    V_ref, V_example : (n, 3) float
        Rest shape (weights, l0, theta0) and example pose (same faces).
    F : (m, 3) int
    alpha : float
        Interpolation weight of the targets (0: the rest shape, 1: the example).
    k_stretch, k_bend : float
        Stiffness k_l of stretching and k_b of bending (dimensionless with the weights above).
    hinges : Hinges, optional
        ``mesh_hinges(F)``, when already computed.
    """
    H = mesh_hinges(F) if hinges is None else hinges
    lbar = edge_lengths(V_ref, H.edges)
    lbar_h = edge_lengths(V_ref, H.hinges[:, :2])
    area = face_areas(V_ref, F)[H.hinge_faces].sum(axis=1)
    theta0 = dihedral_angles(V_ref, H.hinges)
    lengths = lbar + alpha * (edge_lengths(V_example, H.edges) - lbar)
    angles = theta0 + alpha * wrap_angle(dihedral_angles(V_example, H.hinges) - theta0)
    return ShellEnergy(H, np.sqrt(k_stretch) / lbar, np.sqrt(k_bend * lbar_h ** 2 / area), lengths, angles,
                       len(V_ref))


def handle_vertices(V, count=3):
    """``count`` far-apart vertices of ``V`` (n, 3) float by farthest-point sampling, (count,) int64.

    Starts from the vertex farthest from the centroid; deterministic (ties: lowest index).
    """
    chosen = [int(np.argmax(np.linalg.norm(V - V.mean(axis=0), axis=1)))]
    dist = np.linalg.norm(V - V[chosen[0]], axis=1)
    while len(chosen) < count:
        chosen.append(int(np.argmax(dist)))
        dist = np.minimum(dist, np.linalg.norm(V - V[chosen[-1]], axis=1))
    return np.array(chosen, dtype=np.int64)


@dataclass
class SolveResult:
    """Outcome of :func:`gauss_newton`.

    ``V`` (n, 3) float final positions; ``errors`` (iterations + 1,) energy after every accepted
    step (``errors[0]`` at the start); ``steps`` (iterations,) accepted step lengths; ``reason`` one
    of ``STOP_REASONS``; ``gradient_reduction`` |J^T r| at the start over at the end;
    ``min_area_ratio`` smallest face area over its rest area at the end.
    """
    V: np.ndarray
    errors: np.ndarray
    steps: np.ndarray
    converged: bool
    reason: str
    gradient_reduction: float
    min_area_ratio: float
    seconds: float = 0.0

    @property
    def iterations(self):
        return len(self.steps)


@dataclass
class SolverSettings:
    """Stopping rules of :func:`gauss_newton` (see there); dimensionless."""
    max_iters: int = 200        # Gauss-Newton iterations at most
    rel_tol: float = 1e-6       # stop when (E_prev - E) / E_prev falls below this
    energy_tol: float = 1e-16   # E at or below this is zero: converged
    gradient_drop: float = 1e4  # converged: a full step accepted and |J^T r| reduced this much
    min_step: float = 1e-10     # line search: halve from 1 down to this, then give up
    stall_step: float = 1e-3    # an accepted step below this is a creeping step ...
    stall_iters: int = 10       # ... and this many in a row stop the run as stalled
    collapse: float = 1e-5      # a face below this fraction of its rest area has collapsed


def gauss_newton(energy, V0, handles, handle_positions, F, settings=None, log=None):
    """Minimize a :class:`ShellEnergy` by Gauss–Newton with step halving, handles fixed.

    Each iteration solves J^T J d = -J^T r over the free coordinates (sparse LU with a
    fill-reducing ordering of the symmetric matrix), then tries steps 1, 1/2, 1/4, ... and
    accepts the first that lowers the energy. It stops when the energy is zero, when the
    relative decrease falls below ``rel_tol``, when no step lowers it, after ``stall_iters``
    creeping steps in a row, or after ``max_iters``.

    "Converged" means it: the energy is zero (``energy_tol``), or the last step was a full one and
    |J^T r| dropped by ``gradient_drop`` from the start. Anything else is not converged, with the
    reason: "collapsed triangle" when a face ended below ``collapse`` of its rest area (the bending
    gradient grows like 1 / area), otherwise "line-search failure", "max_iters" or "stall".

    Parameters
    ----------
    energy : ShellEnergy
    V0 : (n, 3) float
        Start positions (the handles are moved to ``handle_positions`` first).
    handles : (k,) int
        Fixed vertices (k >= 3 not collinear removes the rigid motions).
    handle_positions : (k, 3) float
    F : (m, 3) int
        Faces (for the collapse check).
    settings : SolverSettings, optional
    log : logging.Logger, optional
        Gets one line per iteration at debug level.

    Returns
    -------
    SolveResult
    """
    s = settings or SolverSettings()
    start = time.perf_counter()
    V = np.array(V0, dtype=float)
    V[handles] = handle_positions
    free = np.ones(3 * energy.n, dtype=bool)
    free[(3 * np.asarray(handles)[:, None] + np.arange(3)).reshape(-1)] = False
    rest_area = face_areas(np.asarray(V0, dtype=float), F)
    r = energy.residuals(V)
    errors, steps = [float(r @ r)], []
    g0 = g = None
    reason, creeping = "max_iters", 0
    normal = _NormalEquations()
    for _ in range(s.max_iters + 1):
        J = energy.jacobian(V)[:, free]
        g = J.T @ r
        if g0 is None:
            g0 = g
        if errors[-1] <= s.energy_tol:
            reason = "converged"
            break
        if len(steps) == s.max_iters:
            break
        if not np.all(np.isfinite(J.data)):
            reason = "collapsed triangle"
            break
        delta = normal.solve(J, g)
        if delta is None:
            reason = "line-search failure"
            break
        step, accepted = 1.0, None
        while step >= s.min_step:
            X = V.copy()
            X.reshape(-1)[free] += step * delta
            rx = energy.residuals(X)
            ex = float(rx @ rx)
            if ex < errors[-1]:
                accepted = (X, rx, ex)
                break
            step *= 0.5
        if accepted is None:
            reason = "line-search failure"
            break
        V, r, ex = accepted
        decrease = (errors[-1] - ex) / errors[-1]
        errors.append(ex)
        steps.append(step)
        if log is not None:
            log.debug("GN %3d: E %.6e step %.3g", len(steps), ex, step)
        creeping = creeping + 1 if step < s.stall_step else 0
        if creeping >= s.stall_iters:
            reason = "stall"
            break
        if decrease < s.rel_tol and ex > s.energy_tol:
            J = energy.jacobian(V)[:, free]
            g = J.T @ r
            reason = "stall"
            break
    reduction = float(np.linalg.norm(g0) / max(np.linalg.norm(g), 1e-300))
    if reason != "converged" and steps and steps[-1] == 1.0 and reduction >= s.gradient_drop:
        reason = "converged"
    ratio = float(np.min(face_areas(V, F) / np.maximum(rest_area, 1e-300)))
    if reason != "converged" and ratio < s.collapse:
        reason = "collapsed triangle"
    return SolveResult(V, np.array(errors), np.array(steps), reason == "converged", reason, reduction, ratio,
                       time.perf_counter() - start)


def deform_towards(V_ref, F, V_example, alpha, k_stretch=1.0, k_bend=1e-2, handles=None, settings=None,
                   hinges=None, log=None):
    """Example-driven deformation of ``V_ref`` (n, 3) float towards ``alpha`` of ``V_example`` (n, 3).

    Starts from the reference with the ``handles`` (default: three far-apart vertices,
    :func:`handle_vertices`) pinned at their linear blend ``(1 - alpha) V_ref + alpha V_example``
    and runs :func:`gauss_newton` on :func:`shell_energy`. Returns its :class:`SolveResult`.
    """
    h = handle_vertices(V_ref) if handles is None else np.asarray(handles)
    energy = shell_energy(V_ref, F, V_example, alpha, k_stretch, k_bend, hinges)
    pinned = (1.0 - alpha) * V_ref[h] + alpha * V_example[h]
    return gauss_newton(energy, V_ref, h, pinned, F, settings, log)


class _NormalEquations:
    """Solves J^T J d = -g for a sequence of nearby Jacobians.

    Conjugate gradients preconditioned by the last sparse LU factorization (of an earlier, nearby
    J^T J) to a relative residual of ``rtol``; a new factorization when that takes more than
    ``max_cg`` iterations (or none exists yet). The steps are exact Gauss–Newton steps up to
    ``rtol``; factorizations, the cost of an iteration, become rare near convergence.
    """

    def __init__(self, rtol=1e-10, max_cg=12):
        self.rtol, self.max_cg, self.lu, self.factorizations = rtol, max_cg, None, 0

    def solve(self, J, g):
        """The step d, (k,) float; None when J^T J is singular."""
        H = (J.T @ J).tocsc()
        if self.lu is not None:
            M = LinearOperator(H.shape, matvec=self.lu.solve, dtype=float)
            d, info = cg(H, -g, rtol=self.rtol, atol=0.0, maxiter=self.max_cg, M=M)
            if info == 0 and np.all(np.isfinite(d)):
                return d
        try:
            self.lu = splu(H, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        except RuntimeError:  # exactly singular
            self.lu = None
            return None
        self.factorizations += 1
        d = self.lu.solve(-g)
        return d if np.all(np.isfinite(d)) else None
