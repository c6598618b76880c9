"""Closed triangle meshes built from parameters, for the demo library and for tests."""

import numpy as np


def capsule(around=40, cap_rings=8, length_rings=50, radius=0.5, length=6.0):
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
