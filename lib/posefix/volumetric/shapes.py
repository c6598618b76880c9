"""Procedural tetrahedral meshes: the bars and cylinders of S4 Table 3.1 and the unit tests."""

import itertools

import numpy as np

from posefix.volumetric.operators import tet_volumes


def tet_grid(counts, size):
    """A box of ``counts`` (nx, ny, nz) cubes of ``size`` (sx, sy, sz), each split into 6 tets (Kuhn).

    Returns
    -------
    X : ((nx+1)(ny+1)(nz+1), 3) float
        Vertices, the box's corner at the origin; index ``(i (ny+1) + j) (nz+1) + k`` for grid point (i, j, k).
    T : (6 nx ny nz, 4) int64
        Positively oriented tets.
    """
    n = np.asarray(counts)
    axes = [np.linspace(0.0, s, c + 1) for s, c in zip(size, n)]
    X = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    index = np.arange(len(X)).reshape(n + 1)
    cubes = np.stack(np.meshgrid(*[np.arange(c) for c in n], indexing="ij"), axis=-1).reshape(-1, 3)
    tets = []
    for order in itertools.permutations(range(3)):
        corner, path = np.zeros(3, dtype=int), [np.zeros(3, dtype=int)]
        for axis in order:
            corner = corner.copy()
            corner[axis] = 1
            path.append(corner)
        tets.append(np.stack([index[tuple((cubes + p).T)] for p in path], axis=1))
    T = np.concatenate(tets).astype(np.int64)
    flip = tet_volumes(X, T) < 0
    T[flip] = T[flip][:, [0, 2, 1, 3]]
    return X, T


def tet_cylinder(radius, length, rings, layers=2):
    """A cylinder along x: a tet grid of a square rod mapped onto the disc (concentric squares to circles).

    ``layers`` cubes per half width, ``rings`` along the length. Returns ``(X, T)`` like :func:`tet_grid`.
    """
    side = 2 * layers
    X, T = tet_grid((rings, side, side), (length, 2.0, 2.0))
    y, z = X[:, 1] - 1.0, X[:, 2] - 1.0
    square = np.maximum(np.abs(y), np.abs(z))
    norm = np.hypot(y, z)
    scale = np.where(norm > 0, square / np.where(norm > 0, norm, 1.0), 0.0) * radius
    return np.column_stack([X[:, 0], y * scale, z * scale]), T
