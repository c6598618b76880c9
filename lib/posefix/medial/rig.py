"""A stick-figure skeleton, its poses and linear blend skinning (S1 §2, Fig. 1: SSD of the skeletal mesh).

A :class:`Rig` is a tree of joints with rest positions. Every joint but the root starts a bone at its
parent; a pose rotates joints about their rest positions (rotation vectors about the world axes of the
rest pose, radians) and may translate the root. Joint ``j``'s rotation moves every bone below ``j``, so
the bone ``parent -> child`` follows the accumulated transform of ``parent``.

Skinning weights are computed automatically from the distances to the bone segments with a Gaussian
soft-min: ``w_b(p) ∝ exp(-((d_b(p) - min_c d_c(p)) / h)^2)``, so the nearest bone dominates and weights
blend smoothly over a length ``h`` where two bones are nearly equally close (around joints). Points on
a bone get weight ~1 there except within ~``h`` of its ends; the weights are smooth in ``p`` and sum to 1.
"""

from dataclasses import dataclass, field

import numpy as np

from posefix.mesh.rotations import rotation_exp


@dataclass(frozen=True)
class Rig:
    """A stick-figure skeleton.

    Attributes
    ----------
    names : tuple of str
        Joint names, parents before children.
    rest : (J, 3) float
        Joint rest positions (model units).
    parents : (J,) int
        Parent joint index; -1 for the root (exactly one).
    """

    names: tuple
    rest: np.ndarray
    parents: np.ndarray

    @property
    def bones(self):
        """(B, 2) int: ``(parent, child)`` joint indices of every bone, in joint order."""
        child = np.flatnonzero(self.parents >= 0)
        return np.stack([self.parents[child], child], 1)

    def mean_bone_length(self):
        """Mean length of the bones (model units)."""
        b = self.bones
        return float(np.linalg.norm(self.rest[b[:, 1]] - self.rest[b[:, 0]], axis=1).mean())


@dataclass(frozen=True)
class RigPose:
    """A pose of a :class:`Rig`.

    Attributes
    ----------
    rotations : (J, 3, 3) float
        Rotation of every joint about its rest position, in the world frame of the rest pose.
    translation : (3,) float
        Translation of the whole figure (the root).
    """

    rotations: np.ndarray
    translation: np.ndarray = field(default_factory=lambda: np.zeros(3))


def pose_from_rotation_vectors(rig, rotations, translation=(0.0, 0.0, 0.0)):
    """A :class:`RigPose` from rotation vectors per joint name.

    Parameters
    ----------
    rig : Rig
    rotations : dict of str -> (3,) float or list of (3,) float
        Rotation vector (radians) of each named joint; a list is composed in order (the first applied
        first). Joints left out do not rotate.
    translation : (3,) float

    Raises
    ------
    KeyError
        A name that is not a joint of ``rig``.
    """
    R = np.repeat(np.eye(3)[None], len(rig.names), axis=0)
    index = {name: j for j, name in enumerate(rig.names)}
    for name, spec in rotations.items():
        steps = np.atleast_2d(np.asarray(spec, dtype=float))
        for omega in steps:
            R[index[name]] = rotation_exp(omega[None])[0] @ R[index[name]]
    return RigPose(rotations=R, translation=np.asarray(translation, dtype=float))


def joint_transforms(rig, pose):
    """World transforms of the joints: ``x -> A_j x + t_j`` moves what hangs below joint ``j``.

    Returns
    -------
    A : (J, 3, 3) float
        Rotations.
    t : (J, 3) float
        Translations (model units).
    """
    J = len(rig.names)
    A, t = np.empty((J, 3, 3)), np.empty((J, 3))
    for j in range(J):
        Rj, pj = pose.rotations[j], rig.rest[j]
        local_t = pj - Rj @ pj
        p = rig.parents[j]
        if p < 0:
            A[j], t[j] = Rj, local_t + pose.translation
        else:
            A[j], t[j] = A[p] @ Rj, A[p] @ local_t + t[p]
    return A, t


def bone_transforms(rig, pose):
    """Transforms of the bones (those of their parent joints): ``A`` (B, 3, 3), ``t`` (B, 3)."""
    A, t = joint_transforms(rig, pose)
    parent = rig.bones[:, 0]
    return A[parent], t[parent]


def bone_distances(rig, P):
    """Distances of points to the bone segments, (k, B) float (model units)."""
    a, b = rig.rest[rig.bones[:, 0]], rig.rest[rig.bones[:, 1]]
    ab = b - a
    u = np.clip(np.einsum("kbi,bi->kb", P[:, None, :] - a, ab) / np.einsum("bi,bi->b", ab, ab), 0.0, 1.0)
    closest = a + u[..., None] * ab
    return np.linalg.norm(P[:, None, :] - closest, axis=2)


def skinning_weights(rig, P, falloff=0.2):
    """Automatic skinning weights of points: Gaussian soft-min of the bone distances (module docstring).

    Parameters
    ----------
    rig : Rig
    P : (k, 3) float
        Points (the skeletal mesh's vertices, or the mesh's for SSD).
    falloff : float
        Blend length ``h`` relative to the rig's mean bone length.

    Returns
    -------
    (k, B) float
        Non-negative, rows sum to 1.
    """
    d = bone_distances(rig, P)
    h = falloff * rig.mean_bone_length()
    w = np.exp(-(((d - d.min(axis=1, keepdims=True)) / h) ** 2))
    return w / w.sum(axis=1, keepdims=True)


def blend_skin(P, weights, A, t):
    """Linear blend skinning: ``sum_b w_b (A_b p + t_b)``.

    Parameters
    ----------
    P : (k, 3) float
    weights : (k, B) float
    A : (B, 3, 3) float
    t : (B, 3) float

    Returns
    -------
    (k, 3) float
    """
    moved = np.einsum("bij,kj->kbi", A, P) + t[None]
    return np.einsum("kb,kbi->ki", weights, moved)


def blended_linear_maps(weights, A):
    """The linear part of the skinning at each point, ``sum_b w_b A_b``: (k, 3, 3) float."""
    return np.einsum("kb,bij->kij", weights, A)
