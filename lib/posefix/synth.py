"""The built-in demo pose library: a three-bone capsule limb posed by linear blend skinning.

The reference is a capsule along x (radius 0.5, cylinder length 6, hemispherical caps) with a
smooth seeded bump pattern, clean of self-intersections. Two joints at ``x = -1`` and ``x = +1``
split it into three bones; skinning weights blend linearly-smoothly over ``+-0.4`` around each joint.
Each target pose bends one or both joints by 120-150 degrees plus a twist of the last bone about
its axis (30-90 degrees), so linear blend skinning collapses the inner side of the joint into
itself: the classic skinning artifact that S0 repairs (its Fig. 1 and 4).
"""

from dataclasses import dataclass

import numpy as np

from posefix.rotations import rotation_exp

RADIUS = 0.5
LENGTH = 6.0
JOINTS = (-1.0, 1.0)
BLEND = 0.4


@dataclass(frozen=True)
class DemoPose:
    """One target pose: rotation vectors (radians, about the world axes) of the two joints.

    ``twist`` is applied about the child bone's own axis (x) before the bend.
    """

    name: str
    suffix: str
    bend1: tuple
    bend2: tuple
    twist2: float = 0.0


REFERENCE_NAME = "demo-reference"
REFERENCE_SUFFIX = ".obj"
POSES = (
    DemoPose("demo-01", ".obj", (0.0, 0.0, 0.0), (0.0, 0.0, np.radians(135.0)), np.radians(30.0)),
    DemoPose("demo-02", ".ply", (0.0, np.radians(120.0), 0.0), (0.0, 0.0, 0.0), np.radians(60.0)),
    DemoPose("demo-03", ".off.gz", (0.0, np.radians(-120.0), 0.0), (0.0, 0.0, np.radians(120.0)), np.radians(45.0)),
    DemoPose("demo-04", ".obj.gz", (0.0, 0.0, 0.0), (0.0, 0.0, np.radians(150.0)), np.radians(90.0)),
)
"""The demo's target poses, with the file format each is written in (to exercise every reader)."""


def capsule(around=40, cap_rings=8, length_rings=50, radius=RADIUS, length=LENGTH):
    """Closed triangulated capsule along the x axis, centred at the origin.

    Parameters
    ----------
    around : int
        Vertices per ring.
    cap_rings, length_rings : int
        Latitude rings per hemispherical cap, segments along the cylinder.

    Returns
    -------
    V : (2 + around * (2 cap_rings + length_rings - 1), 3) float
    F : (m, 3) int64
        Outward-oriented triangles.
    """
    phi = 0.5 * np.pi * np.arange(1, cap_rings + 1) / cap_rings
    half = 0.5 * length
    xs = np.concatenate([-half - radius * np.cos(phi), np.linspace(-half, half, length_rings + 1)[1:-1],
                         half + radius * np.cos(phi[::-1])])
    rho = np.concatenate([radius * np.sin(phi), np.full(length_rings - 1, radius), radius * np.sin(phi[::-1])])
    theta = 2.0 * np.pi * np.arange(around) / around
    rings = np.stack([np.repeat(xs, around), np.outer(rho, np.cos(theta)).ravel(),
                      np.outer(rho, np.sin(theta)).ravel()], 1)
    V = np.vstack([[-half - radius, 0.0, 0.0], rings, [half + radius, 0.0, 0.0]])
    nr = len(xs)
    idx = 1 + np.arange(nr * around).reshape(nr, around)
    nxt = np.roll(idx, -1, axis=1)
    a, b, c, d = idx[:-1], nxt[:-1], idx[1:], nxt[1:]
    band = np.concatenate([np.stack([a, c, d], -1).reshape(-1, 3), np.stack([a, d, b], -1).reshape(-1, 3)])
    last = len(V) - 1
    caps = np.concatenate([np.stack([np.zeros(around, int), idx[0], nxt[0]], 1),
                           np.stack([np.full(around, last), nxt[-1], idx[-1]], 1)])
    F = np.concatenate([caps, band]).astype(np.int64)
    return V, _orient_outward(V, F)


def _orient_outward(V, F):
    v0, v1, v2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    volume = np.einsum("ij,ij->i", v0, np.cross(v1, v2)).sum()
    return F if volume > 0 else F[:, ::-1].copy()


def bumpy(V, seed, amplitude=0.02):
    """Radially perturb a capsule with a smooth seeded pattern (relative amplitude ``amplitude``)."""
    rng = np.random.default_rng(seed)
    theta = np.arctan2(V[:, 2], V[:, 1])
    bump = np.zeros(len(V))
    for _ in range(6):
        kx, kt = rng.uniform(0.5, 2.0), rng.integers(1, 4)
        bump += np.sin(kx * V[:, 0] + rng.uniform(0, 2 * np.pi)) * np.cos(kt * theta + rng.uniform(0, 2 * np.pi))
    out = V.copy()
    out[:, 1:] *= (1.0 + amplitude * bump / 6.0)[:, None]
    return out


def skinning_weights(x):
    """Weights of the three bones at axial coordinates ``x``, (n, 3) float summing to 1."""
    s1, s2 = (_smoothstep((x - (j - BLEND)) / (2 * BLEND)) for j in JOINTS)
    return np.stack([1.0 - s1, s1 - s2, s2], 1)


def _smoothstep(u):
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def pose_limb(V, pose):
    """Linear blend skinning of the reference limb ``V`` (n, 3) into ``pose``; returns (n, 3)."""
    p1, p2 = (np.array([j, 0.0, 0.0]) for j in JOINTS)
    R1 = rotation_exp(np.array([pose.bend1]))[0]
    R2 = rotation_exp(np.array([pose.bend2]))[0] @ rotation_exp(np.array([[pose.twist2, 0.0, 0.0]]))[0]
    bone1 = (V - p1) @ R1.T + p1
    bone2 = (((V - p2) @ R2.T + p2) - p1) @ R1.T + p1
    w = skinning_weights(V[:, 0])
    return w[:, :1] * V + w[:, 1:2] * bone1 + w[:, 2:3] * bone2


def demo_library(seed=7, around=40):
    """The demo reference and target poses.

    Parameters
    ----------
    seed : int
        Seed of the bump pattern; the library is a deterministic function of it.
    around : int
        Vertices per ring (``around=40`` gives 2,602 vertices and 5,200 faces).

    Returns
    -------
    V_ref : (n, 3) float
    F : (m, 3) int64
    poses : dict of str -> (n, 3) float
        Target poses by name, in :data:`POSES` order.
    """
    V, F = capsule(around=around, length_rings=int(round(1.25 * around)))
    V_ref = bumpy(V, seed)
    return V_ref, F, {p.name: pose_limb(V_ref, p) for p in POSES}
