"""Discrete-shell energy of example-driven deformation (Fröhlich & Botsch 2011).

S0 §5 ("Benefits for subsequent processing") checks repaired poses by how a downstream nonlinear
solver behaves on them; the contact solver's elastic finish minimizes the same energy, with a rest state
taken from the target where it is not distorted (:func:`rest_elastic_energy`). The energy is a sum of squared residuals, one per edge for stretching and
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

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from posefix.mesh.geometry import edge_lengths, face_areas
from posefix.mesh.distortion import face_distortion
from posefix.mesh.topology import edges
from posefix.mesh.tolerances import TINY



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
    e_hat = e / np.maximum(np.linalg.norm(e, axis=1), TINY)[:, None]
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

    Build with :func:`shell_energy` (or :func:`rest_elastic_energy`). ``residuals(V)`` gives r (e + h,),
    ``jacobian(V)`` the sparse d r / d vec(V) ((e + h, 3 n) CSR, column ``3 v + c`` for coordinate c of vertex v);
    the energy is ``r . r`` (dimensionless). With ``log_strain`` the stretching residuals are
    ``w_l log(l_e / l*_e)``: a stretch and the crush by its inverse cost the same, and a collapsed edge costs
    without bound (the linear ``w_l (l_e - l*_e)`` costs at most ``w_l l*_e`` for it).
    """
    hinges: Hinges
    w_stretch: np.ndarray      # (e,) w_l
    w_bend: np.ndarray         # (h,) w_b
    length_target: np.ndarray  # (e,) l*
    angle_target: np.ndarray   # (h,) theta*
    n: int
    log_strain: bool = False
    _order: np.ndarray = field(repr=False, default=None)    # Jacobian entries in CSR order
    _indices: np.ndarray = field(repr=False, default=None)  # their columns
    _indptr: np.ndarray = field(repr=False, default=None)   # the rows' starts in them

    def __post_init__(self):
        E, H = self.hinges.edges, self.hinges.hinges
        e, h = len(E), len(H)
        rows_l = np.repeat(np.arange(e), 6)
        cols_l = (3 * E[:, [0, 0, 0, 1, 1, 1]] + np.tile([0, 1, 2], 2)).reshape(-1)
        rows_b = np.repeat(e + np.arange(h), 12)
        cols_b = (3 * np.repeat(H, 3, axis=1) + np.tile([0, 1, 2], 4)).reshape(-1)
        rows, cols = np.r_[rows_l, rows_b], np.r_[cols_l, cols_b]
        self._order = np.lexsort((cols, rows))  # the CSR pattern, built once
        self._indices = cols[self._order]
        self._indptr = np.r_[0, np.cumsum(np.bincount(rows, minlength=e + h))]

    def residuals(self, V):
        """Residuals r, (e + h,) float: stretching rows first, then bending rows."""
        lengths = edge_lengths(V, self.hinges.edges)
        if self.log_strain:
            rl = self.w_stretch * np.log(np.maximum(lengths, TINY) / self.length_target)
        else:
            rl = self.w_stretch * (lengths - self.length_target)
        rb = self.w_bend * wrap_angle(dihedral_angles(V, self.hinges.hinges) - self.angle_target)
        return np.r_[rl, rb]

    def jacobian_values(self, V):
        """Entries of the Jacobian in the fixed pattern (``jacobian`` builds the matrix from them)."""
        E = self.hinges.edges
        d = V[E[:, 1]] - V[E[:, 0]]
        lengths = np.maximum(np.linalg.norm(d, axis=1), TINY)
        u = d / (lengths ** 2 if self.log_strain else lengths)[:, None]
        gl = self.w_stretch[:, None] * np.c_[-u, u]
        gb = self.w_bend[:, None] * dihedral_gradients(V, self.hinges.hinges).reshape(len(self.w_bend), 12)
        return np.r_[gl.reshape(-1), gb.reshape(-1)]

    def jacobian(self, V):
        """Sparse Jacobian d r / d vec(V), (e + h, 3 n) CSR."""
        shape = (len(self.w_stretch) + len(self.w_bend), 3 * self.n)
        return sp.csr_matrix((self.jacobian_values(V)[self._order], self._indices, self._indptr), shape=shape)

    def energy(self, V):
        """Energy sum r^2 at ``V`` (n, 3) float (dimensionless)."""
        r = self.residuals(V)
        return float(r @ r)

    def restricted(self, moving):
        """The terms with a vertex in ``moving`` ((n,) bool): the same energy up to a constant, and the same
        gradient and Hessian over those vertices, while the others stay put."""
        H = self.hinges
        e, h = moving[H.edges].any(axis=1), moving[H.hinges].any(axis=1)
        return ShellEnergy(Hinges(H.edges[e], H.hinges[h], H.hinge_faces[h]), self.w_stretch[e], self.w_bend[h],
                           self.length_target[e], self.angle_target[h], self.n, self.log_strain)


@dataclass
class FaceAreaEnergy:
    """Log-area residuals ``w_f log(A_f / A*_f)`` of a triangle mesh's faces: a face collapsed toward zero area costs
    without bound, which edge lengths alone do not ensure (a sliver keeps its edges).

    Attributes
    ----------
    faces : (m, 3) int
    weights : (m,) float
        ``w_f``.
    area_target : (m,) float
        ``A*_f``, positive.
    n : int
        Vertex count.
    """
    faces: np.ndarray
    weights: np.ndarray
    area_target: np.ndarray
    n: int

    def residuals(self, V):
        """Residuals, (m,) float."""
        return self.weights * np.log(np.maximum(face_areas(V, self.faces), TINY) / self.area_target)

    def jacobian(self, V):
        """Sparse Jacobian d r / d vec(V), (m, 3 n) CSR: ``d A / d x_i = 1/2 n_hat x (x_k - x_j)`` for the corners
        ``(i, j, k)`` of a face in order."""
        F = self.faces
        cross = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
        double = np.maximum(np.linalg.norm(cross, axis=1), TINY)
        unit = cross / double[:, None]
        grads = [np.cross(unit, V[F[:, (c + 2) % 3]] - V[F[:, (c + 1) % 3]]) for c in range(3)]
        values = np.stack(grads, axis=1) * (self.weights / double)[:, None, None]  # d log A = dA / A, A = double / 2
        cols = (3 * np.repeat(F, 3, axis=1) + np.tile([0, 1, 2], 3)).reshape(-1)
        rows = np.repeat(np.arange(len(F)), 9)
        return sp.csr_matrix((values.reshape(-1), (rows, cols)), shape=(len(F), 3 * self.n))

    def restricted(self, moving):
        """The faces with a vertex in ``moving`` ((n,) bool) (:meth:`ShellEnergy.restricted`)."""
        f = moving[self.faces].any(axis=1)
        return FaceAreaEnergy(self.faces[f], self.weights[f], self.area_target[f], self.n)


@dataclass
class ElasticEnergy:
    """A sum of squared residuals of several terms (:class:`ShellEnergy`, :class:`FaceAreaEnergy`), ``r . r``."""
    terms: list

    def residuals(self, V):
        """The terms' residuals one after the other, float array."""
        return np.concatenate([t.residuals(V) for t in self.terms])

    def jacobian(self, V):
        """The terms' Jacobians stacked, CSR."""
        return sp.vstack([t.jacobian(V) for t in self.terms], format="csr")

    def energy(self, V):
        """Energy ``r . r`` at ``V`` (n, 3) float (dimensionless)."""
        r = self.residuals(V)
        return float(r @ r)

    def restricted(self, moving):
        """Every term's residuals with a vertex in ``moving`` ((n,) bool): the energy up to a constant while the
        other vertices stay put, at the cost of the moving region (kids-0001: 11k of 60k vertices move).

        Examples
        --------
        >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]); F = np.array([[0, 1, 2], [2, 1, 3]])
        >>> full = rest_elastic_energy(V, F, V, 4.0, 1.0); part = full.restricted(np.array([0, 0, 0, 1], bool))
        >>> X = V + [[0, 0, 0], [0, 0, 0], [0, 0, 0], [0.3, -0.2, 0.5]]
        >>> bool(np.isclose(full.energy(X) - part.energy(X), full.energy(V) - part.energy(V)))
        True
        """
        return ElasticEnergy([t.restricted(moving) for t in self.terms])


def shell_energy(V_ref, F, V_example, alpha, k_bend, k_stretch=1.0, hinges=None):
    """Example-driven shell energy: deform ``V_ref`` towards ``alpha`` of the way to ``V_example``.

    Parameters
    ----------
    V_ref, V_example : (n, 3) float
        Rest shape (weights, l0, theta0) and example pose (same faces).
    F : (m, 3) int
    alpha : float
        Interpolation weight of the targets (0: the rest shape, 1: the example).
    k_bend, k_stretch : float
        Stiffness k_b of bending and k_l of stretching (dimensionless with the weights above).
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


def rest_elastic_energy(V_ref, F, V_pose, limit, k_bend, hinges=None):
    """Elastic energy (shell and face areas) whose rest state is ``V_pose``'s shape within ``limit`` of ``V_ref``'s.

    An edge's rest length is the pose's, clipped to ``[l_ref / limit, limit l_ref]``; a face's rest area likewise
    the pose's clipped to ``[A_ref / limit, limit A_ref]``; a hinge's rest angle is the pose's where both its faces
    are within ``limit`` of the reference (edge-length and area ratios,
    :func:`posefix.mesh.distortion.face_distortion`), the reference's elsewhere. So a stretched or collapsed region
    of the pose (an LBS candy wrapper, a crushed fold) does not become the rest state beyond what the limit
    tolerates. Stretching and areas are measured as log-strain (weights 1: a face crushed costs as much as one
    stretched by the inverse ratio, a collapse without bound); bending's weights are the reference's
    (:func:`shell_energy`).

    Parameters
    ----------
    V_ref, V_pose : (n, 3) float
        Reference and pose positions (same faces).
    F : (m, 3) int
    limit : float
        Largest ratio of a rest length or area to the reference's (and of face shapes for the angles), > 1.
    k_bend : float
        Bending stiffness ``k_b``.
    hinges : Hinges, optional
        ``mesh_hinges(F)``, when already computed.

    Returns
    -------
    ElasticEnergy
        ``[ShellEnergy, FaceAreaEnergy]``; zero at ``V_pose`` when no face of the pose is beyond ``limit``.

    Examples
    --------
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]); F = np.array([[0, 1, 2], [2, 1, 3]])
    >>> shell, areas = rest_elastic_energy(V, F, V * [8.0, 1.0, 1.0], 4.0, 1e-2).terms
    >>> shell.length_target.round(3).tolist(), areas.area_target.tolist()  # 8x stretched: at rest at 4x
    ([4.0, 1.0, 5.657, 1.0, 4.0], [2.0, 2.0])
    """
    H = mesh_hinges(F) if hinges is None else hinges
    shell = shell_energy(V_ref, F, V_pose, 1.0, k_bend, hinges=H)
    reference = edge_lengths(V_ref, H.edges)
    shell.length_target = np.clip(shell.length_target, reference / limit, reference * limit)
    edge, area = face_distortion(V_pose, V_ref, F)
    keep = ((edge <= limit) & (area <= limit))[H.hinge_faces].all(axis=1)
    shell.angle_target = np.where(keep, shell.angle_target, dihedral_angles(V_ref, H.hinges))
    shell.log_strain, shell.w_stretch = True, np.ones(len(H.edges))
    rest = face_areas(V_ref, F)
    areas = np.clip(face_areas(V_pose, F), rest / limit, rest * limit)
    return ElasticEnergy([shell, FaceAreaEnergy(np.asarray(F), np.ones(len(F)), areas, len(V_ref))])
