"""Rotations: polar decomposition, SO(3) log/exp, rigid alignment, and branch unwrapping.

Rotation vectors ``omega`` are axis * angle (radians); arrays of matrices have shape (m, 3, 3).
"""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components, minimum_spanning_tree

from posefix.mesh.tolerances import ROUNDOFF, SMALL_ANGLE


def polar_decomposition(J):
    """Polar decomposition ``J = R S`` with ``R`` a proper rotation and ``S`` symmetric.

    Parameters
    ----------
    J : (m, 3, 3) float

    Returns
    -------
    R : (m, 3, 3) float
        Rotations (det +1). When ``det J < 0`` the reflection is moved into ``S``.
    S : (m, 3, 3) float
        Symmetric stretch; positive semi-definite unless ``det J < 0``.
    """
    U, s, Vt = np.linalg.svd(J)
    flip = np.linalg.det(U @ Vt) < 0
    U[flip, :, 2] *= -1.0
    s[flip, 2] *= -1.0
    R = U @ Vt
    S = np.einsum("mki,mk,mkj->mij", Vt, s, Vt)
    return R, S


def cofactors(H):
    """Cofactor matrices ``det(H) H^-T`` of 3x3 matrices (rows: cross products of row pairs), (m, 3, 3)."""
    r0, r1, r2 = H[:, 0], H[:, 1], H[:, 2]
    return np.stack([np.cross(r1, r2), np.cross(r2, r0), np.cross(r0, r1)], axis=1)


def polar_rotations(J, tol=1e-13, max_steps=30):
    """Rotation factors of the polar decomposition ``J = R S``, by scaled Newton iteration (Higham 1986).

    ``H <- (g H + H^-T / g) / 2`` with ``g = (|H^-1| / |H|)^(1/2)`` (Frobenius), the inverse from closed-form
    cofactors: the same ``R`` as :func:`polar_decomposition` to rounding, many times faster for large
    batches. Matrices with ``det J <= 0`` take :func:`polar_decomposition` (the reflection moved into ``S``).

    Parameters
    ----------
    J : (m, 3, 3) float
    tol : float
        Stop when no entry changes by more than this in a step.
    max_steps : int

    Returns
    -------
    (m, 3, 3) float
    """
    H = np.array(J, dtype=float)
    flipped = np.linalg.det(H) <= 0
    H[flipped] = np.eye(3)
    for _ in range(max_steps):
        C = cofactors(H)
        inv_t = C / np.einsum("mij,mij->m", H[:, :1], C[:, :1])[:, None, None]  # det = row 0 . cofactor row 0
        g = np.sqrt(np.linalg.norm(inv_t, axis=(1, 2)) / np.linalg.norm(H, axis=(1, 2)))[:, None, None]
        H_next = 0.5 * (g * H + inv_t / g)
        done = np.abs(H_next - H).max() <= tol
        H = H_next
        if done:
            break
    if flipped.any():
        H[flipped] = polar_decomposition(J[flipped])[0]
    return H


def rotation_log(R):
    """Rotation vectors of rotation matrices, angle in [0, pi].

    Uses the quaternion (Shepperd's method) and ``angle = 2 atan2(|v|, w)``, accurate near both
    0 and pi; at exactly pi the axis sign is arbitrary.

    Parameters
    ----------
    R : (m, 3, 3) float

    Returns
    -------
    (m, 3) float
    """
    q = rotation_to_quaternion(R)
    w, v = q[:, 0], q[:, 1:]
    nv = np.linalg.norm(v, axis=1)
    angle = 2.0 * np.arctan2(nv, w)
    small = nv < ROUNDOFF
    scale = np.where(small, 2.0 / np.where(small, w, 1.0), angle / np.where(small, 1.0, nv))
    return v * scale[:, None]


def rotation_to_quaternion(R):
    """Unit quaternions ``(w, x, y, z)`` with ``w >= 0``, (m, 4) float (Shepperd's method)."""
    m = len(R)
    tr = np.trace(R, axis1=1, axis2=2)
    diag = np.stack([tr, R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]], 1)
    case = np.argmax(diag, axis=1)
    q = np.empty((m, 4))
    for c in range(4):
        idx = np.flatnonzero(case == c)
        if len(idx) == 0:
            continue
        r = R[idx]
        if c == 0:
            s = 2.0 * np.sqrt(1.0 + tr[idx])
            q[idx] = np.stack([0.25 * s, (r[:, 2, 1] - r[:, 1, 2]) / s,
                               (r[:, 0, 2] - r[:, 2, 0]) / s, (r[:, 1, 0] - r[:, 0, 1]) / s], 1)
        else:
            i = c - 1
            j, k = (i + 1) % 3, (i + 2) % 3
            s = 2.0 * np.sqrt(np.maximum(1.0 + r[:, i, i] - r[:, j, j] - r[:, k, k], 0.0))
            qq = np.empty((len(idx), 4))
            qq[:, 0] = (r[:, k, j] - r[:, j, k]) / s
            qq[:, 1 + i] = 0.25 * s
            qq[:, 1 + j] = (r[:, j, i] + r[:, i, j]) / s
            qq[:, 1 + k] = (r[:, k, i] + r[:, i, k]) / s
            q[idx] = qq
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def rotation_exp(omega):
    """Rotation matrices of rotation vectors (Rodrigues), (m, 3, 3) float."""
    theta = np.linalg.norm(omega, axis=1)
    small = theta < SMALL_ANGLE
    t = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - theta ** 2 / 6.0, np.sin(t) / t)
    b = np.where(small, 0.5 - theta ** 2 / 24.0, (1.0 - np.cos(t)) / t ** 2)
    K = np.zeros((len(omega), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -omega[:, 2], omega[:, 1], -omega[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = omega[:, 2], -omega[:, 1], omega[:, 0]
    return np.eye(3) + a[:, None, None] * K + b[:, None, None] * (K @ K)


def rotation_angle_between(Ra, Rb):
    """Angle of ``Ra^T Rb`` in [0, pi], (m,) float."""
    return np.linalg.norm(rotation_log(np.transpose(Ra, (0, 2, 1)) @ Rb), axis=1)


def kabsch(X, Y, w):
    """Weighted rigid alignment: the rotation ``R`` and centroids with ``Y ~ R (X - cx) + cy``.

    Parameters
    ----------
    X, Y : (n, 3) float
        Corresponding points.
    w : (n,) float
        Non-negative weights, not all zero.

    Returns
    -------
    R : (3, 3) float
        Proper rotation minimizing ``sum w |R (x - cx) - (y - cy)|^2``.
    cx, cy : (3,) float
        Weighted centroids.
    """
    w = w / w.sum()
    cx, cy = w @ X, w @ Y
    H = (X - cx).T @ ((Y - cy) * w[:, None])
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0
    R = Vt.T @ np.diag([1.0, 1.0, d]) @ U.T
    return R, cx, cy


def unwrap_rotation_vectors(omega, pairs):
    """Choose a globally consistent branch for a field of rotation vectors.

    A rotation by ``theta`` about ``a`` is also ``(theta + 2 pi k) a`` for any integer ``k``
    (with ``theta`` in [0, pi] the axis flips sign as a smooth field passes through pi). Like
    quality-guided phase unwrapping, the faces are visited along a minimum spanning tree of the
    face graph weighted by the (branch-independent) angle between neighbouring rotations,
    starting in each component from the face with the smallest rotation, and each face takes the
    ``k`` that brings its vector closest to its parent's.

    Parameters
    ----------
    omega : (m, 3) float
        Rotation vectors with angles in [0, pi] (from :func:`rotation_log`).
    pairs : (k, 2) int
        Neighbouring faces (:func:`posefix.mesh.topology.face_adjacency`).

    Returns
    -------
    omega : (m, 3) float
        Same rotations, unwrapped: ``rotation_exp`` of the result equals that of the input.
    turns : (m,) int
        The ``k`` chosen per face.
    """
    m = len(omega)
    theta = np.linalg.norm(omega, axis=1)
    axis = omega / np.where(theta > 0, theta, 1.0)[:, None]
    R = rotation_exp(omega)
    gap = rotation_angle_between(R[pairs[:, 0]], R[pairs[:, 1]]) + 1e-9
    W = sp.coo_matrix((gap, (pairs[:, 0], pairs[:, 1])), shape=(m, m)).tocsr()
    tree = minimum_spanning_tree(W)
    tree = tree + tree.T
    ncomp, labels = connected_components(tree, directed=False)
    out, turns = omega.copy(), np.zeros(m, dtype=np.int64)
    for c in range(ncomp):
        members = np.flatnonzero(labels == c)
        root = members[np.argmin(theta[members])]
        order, parent = breadth_first_order(tree, root, directed=False)
        _unwrap_along(order, parent, theta, axis, out, turns)
    return out, turns


def _unwrap_along(order, parent, theta, axis, out, turns):
    """Visit ``order`` (parents first) and pick each face's turn count relative to its parent."""
    two_pi = 2.0 * np.pi
    ax = axis.tolist()
    th = theta.tolist()
    cur = out.tolist()
    for f in order[1:].tolist():
        p = cur[parent[f]]
        a = ax[f]
        k = round(((p[0] * a[0] + p[1] * a[1] + p[2] * a[2]) - th[f]) / two_pi)
        if k:
            s = th[f] + two_pi * k
            cur[f] = [s * a[0], s * a[1], s * a[2]]
            turns[f] = k
    out[:] = np.asarray(cur)
