"""Key frames by gradient-space interpolation (S0 §4.1, after Xu et al. 2005).

For a reference ``V_ref`` and a target ``V_tgt`` with the same faces:

1. **Global alignment** (optional, default on): a weighted Kabsch fit ``V_tgt ~ R_g (V_ref - c_ref)
   + c_tgt`` (barycentric vertex areas as weights). The per-face analysis below runs on the
   target with that rigid motion removed; the motion is put back per frame with the rotation
   interpolated on SO(3) (``exp(t log R_g)``) and the centroid linearly.
2. **Per-face deformation gradient** ``J = [e1', e2', n'] [e1, e2, n]^-1`` from the two edges and the
   normal scaled by ``1/sqrt(|n|)`` (Sumner & Popovic 2004), **polar decomposition** ``J = R S``.
3. **Rotation branch**: rotation vectors ``log R`` are unwrapped over the face adjacency
   (:func:`posefix.mesh.rotations.unwrap_rotation_vectors`) so that neighbouring faces take the same
   path through SO(3) (a tail twisted past 180 degrees keeps twisting instead of tearing).
4. **Frame ``t``**: ``J(t) = exp(t log R) ((1 - t) I + t S)`` per face, then the Poisson problem
   ``min sum_f A_f |grad x - J(t)|^2``, i.e. ``L x = G^T M J(t)`` with the cotangent Laplacian of the
   reference, factorized once and reused for every frame. The translation of each connected
   component is fixed by interpolating its weighted centroid linearly.

``t = 0`` gives the reference and ``t = 1`` the target (up to solver round-off).
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from posefix.io.keyframes import stored_frames
from posefix.mesh.geometry import vertex_areas
from posefix.mesh.laplacian import cotangent_laplacian, face_mass, gradient_operator
from posefix.mesh.rotations import kabsch, polar_decomposition, rotation_exp, rotation_log, unwrap_rotation_vectors
from posefix.mesh.sparse import factorized
from posefix.mesh.topology import face_adjacency, vertex_components


@dataclass
class Interpolation:
    """Everything needed to evaluate a frame; built once per (reference, target) pair.

    Attributes
    ----------
    omega : (m, 3) float
        Per-face rotation vectors (after alignment and unwrapping), radians.
    turns : (m,) int
        Branch shifts chosen by the unwrapping (0 where the principal branch was kept).
    stretch : (m, 3, 3) float
        Per-face symmetric stretch ``S``.
    global_omega : (3,) float
        Rotation vector of the global alignment.
    c_ref, c_tgt : (3,) float
        Weighted centroids of reference and target.
    comp_ref, comp_tgt : (c, 3) float
        Per-component weighted centroids of the reference and of the aligned target.
    """

    F: np.ndarray
    omega: np.ndarray
    turns: np.ndarray
    stretch: np.ndarray
    global_omega: np.ndarray
    c_ref: np.ndarray
    c_tgt: np.ndarray
    comp_ref: np.ndarray
    comp_tgt: np.ndarray
    labels: np.ndarray
    weights: np.ndarray
    GtM: sp.csr_matrix
    solver: object
    free: np.ndarray


def prepare(V_ref, V_tgt, F, align=True, unwrap=True):
    """Analyse a reference/target pair and factorize the Poisson system.

    Parameters
    ----------
    V_ref, V_tgt : (n, 3) float
    F : (m, 3) int
        Faces of the reference must have non-zero area.
    align : bool
        Remove the global rigid motion before the per-face analysis.
    unwrap : bool
        Unwrap rotation branches over the face adjacency.

    Returns
    -------
    Interpolation
    """
    n = len(V_ref)
    weights = vertex_areas(V_ref, F)
    R_g, c_ref, c_tgt = kabsch(V_ref, V_tgt, weights)
    if not align:
        R_g = np.eye(3)
    aligned = (V_tgt - c_tgt) @ R_g + c_ref
    R, S = polar_decomposition(deformation_gradients(V_ref, aligned, F))
    omega = rotation_log(R)
    turns = np.zeros(len(F), dtype=np.int64)
    if unwrap:
        omega, turns = unwrap_rotation_vectors(omega, face_adjacency(F))
    labels, count = vertex_components(F, n)
    GtM = (gradient_operator(V_ref, F).T @ face_mass(V_ref, F)).tocsr()
    L = cotangent_laplacian(V_ref, F)
    anchors = np.unique(labels, return_index=True)[1]
    free = np.setdiff1d(np.arange(n), anchors)
    solver = factorized(L[free][:, free], ordering="MMD_AT_PLUS_A", symmetric=True) if len(free) else None
    return Interpolation(
        F=F, omega=omega, turns=turns, stretch=S, global_omega=rotation_log(R_g[None])[0],
        c_ref=c_ref, c_tgt=c_tgt,
        comp_ref=_component_centroids(V_ref, labels, count, weights),
        comp_tgt=_component_centroids(aligned, labels, count, weights),
        labels=labels, weights=weights, GtM=GtM, solver=solver, free=free)


def frame(interp, t):
    """Vertex positions of the interpolated shape at time ``t`` in [0, 1], (n, 3) float."""
    J = rotation_exp(t * interp.omega) @ ((1.0 - t) * np.eye(3) + t * interp.stretch)
    rhs = interp.GtM @ np.transpose(J, (0, 2, 1)).reshape(-1, 3)
    n = len(interp.labels)
    x = np.zeros((n, 3))
    if interp.solver is not None:
        x[interp.free] = interp.solver.solve(np.ascontiguousarray(rhs[interp.free]))
    count = len(interp.comp_ref)
    target = (1.0 - t) * interp.comp_ref + t * interp.comp_tgt
    x += (target - _component_centroids(x, interp.labels, count, interp.weights))[interp.labels]
    R_t = rotation_exp(t * interp.global_omega[None])[0]
    centre = (1.0 - t) * interp.c_ref + t * interp.c_tgt
    return (x - interp.c_ref) @ R_t.T + centre


def keyframes(V_ref, V_tgt, F, count=11, align=True, unwrap=True):
    """Key frames at ``t = k / (count - 1)``, as the stage keyframes stores them: ``V_ref`` and ``V_tgt`` at the
    ends, the inner frames to float32 precision of their offsets from the linear blend
    (:func:`posefix.io.keyframes.stored_frames`, about 1e-8 of the bounding-box diagonal).

    Returns
    -------
    frames : (count, n, 3) float
    t : (count,) float
    interp : Interpolation
        The analysis, for diagnostics (rotation angles, branch shifts).
    """
    interp = prepare(V_ref, V_tgt, F, align=align, unwrap=unwrap)
    t = np.linspace(0.0, 1.0, count)
    return stored_frames(np.stack([frame(interp, ti) for ti in t]), t, V_ref, V_tgt), t, interp


def deformation_gradients(V_ref, V_def, F):
    """Per-face deformation gradients from ``V_ref`` to ``V_def``, (m, 3, 3) float.

    ``J`` maps the reference frame ``[e1, e2, n / sqrt|n|]`` onto the deformed one; faces that
    collapse to zero area in ``V_def`` get a zero normal column (``J`` then has rank <= 2).
    """
    return _frames(V_def, F) @ np.linalg.inv(_frames(V_ref, F))


def _frames(V, F):
    e1 = V[F[:, 1]] - V[F[:, 0]]
    e2 = V[F[:, 2]] - V[F[:, 0]]
    n = np.cross(e1, e2)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = n / np.sqrt(np.where(length > 0, length, 1.0))
    return np.stack([e1, e2, n], axis=2)


def _component_centroids(X, labels, count, weights):
    """Weighted centroid per component, (count, 3); uniform weights where a component has no area."""
    total = np.bincount(labels, weights=weights, minlength=count)
    w = np.where(total[labels] > 0, weights, 1.0)
    total = np.bincount(labels, weights=w, minlength=count)
    sums = np.stack([np.bincount(labels, weights=w * X[:, c], minlength=count) for c in range(3)], 1)
    return sums / total[:, None]
