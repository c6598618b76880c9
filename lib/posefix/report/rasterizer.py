"""Offscreen mesh renders for the reports (matplotlib, no screen needed).

A mesh is drawn by orthographic projection with a fixed camera per library (:func:`camera`), flat
Lambert shading (two-sided) and the painter's algorithm (faces sorted far to near). Highlighted
faces (intersecting ones) are drawn once more on top, half transparent, so that they stay visible
where other surface hides them ("x-ray"). Functions draw into matplotlib axes and return nothing
but the artists they add; the stage scripts own the figures and write them.
"""

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.colors import Normalize

SURFACE = np.array([0.78, 0.78, 0.80])
"""Base colour of an unhighlighted face, RGB in [0, 1]."""
HIGHLIGHT = np.array([0.90, 0.10, 0.10])
"""Colour of highlighted faces (intersecting, or new)."""
SECONDARY = np.array([1.00, 0.60, 0.00])
"""Colour of secondary highlights (intersections the reference has too)."""
DISTORTED = np.array([0.55, 0.20, 0.80])
"""Colour of distorted faces (stretched or crushed beyond the distortion limit)."""
LIGHT = np.array([0.35, 0.55, 0.76])
"""Light direction in camera coordinates (x right, y up, z towards the viewer), unit length."""


def camera(V, azimuth=30.0, elevation=15.0):
    """Camera rotation of a library, from its reference: looks across the mesh's thinnest side.

    The view axis is the bounding-box axis of least extent (the side view of an animal), turned by
    ``azimuth`` degrees about the up axis and tilted by ``elevation`` degrees; up is the +y axis
    unless that is the view axis (then +z).

    Parameters
    ----------
    V : (n, 3) float
        Reference vertex positions.

    Returns
    -------
    R : (3, 3) float
        Rows: the camera's right, up and towards-viewer axes in world coordinates.
    """
    view = int(np.argmin(np.ptp(V, axis=0)))
    up = 1 if view != 1 else 2
    right = 3 - view - up
    R = np.zeros((3, 3))
    R[0, right], R[1, up] = 1.0, 1.0
    R[2] = np.cross(R[0], R[1])
    a, e = np.radians(azimuth), np.radians(elevation)
    turn = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    tilt = np.array([[1, 0, 0], [0, np.cos(e), -np.sin(e)], [0, np.sin(e), np.cos(e)]])
    return tilt @ turn @ R


def shading(V, F, R):
    """Two-sided Lambert factor per face in [0.3, 1] under :data:`LIGHT`, (m,) float."""
    tri = V[F] @ R.T
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(normal, axis=1)
    cosine = np.abs(normal @ LIGHT) / np.where(length > 0, length, 1.0)
    return 0.3 + 0.7 * cosine


def draw_mesh(ax, V, F, R, colors=None, highlight=(), scale=None):
    """Draw a shaded mesh into 2-D axes.

    Parameters
    ----------
    ax : matplotlib Axes
    V : (n, 3) float
    F : (m, 3) int
    R : (3, 3) float
        Camera rotation (:func:`camera`).
    colors : (m, 3) float, optional
        RGB per face before shading; :data:`SURFACE` by default.
    highlight : sequence of ((m,) bool, (3,) float)
        Faces drawn again on top, half transparent, in the given colour.
    scale : (2, 2) float, optional
        Axis limits ``[[xmin, xmax], [ymin, ymax]]`` in camera coordinates (the same for meshes
        compared side by side); by default the mesh's own extent.
    """
    tri = V[F] @ R.T
    base = np.broadcast_to(SURFACE, (len(F), 3)) if colors is None else np.asarray(colors)[:, :3]
    rgb = np.clip(base * shading(V, F, R)[:, None], 0, 1)
    order = np.argsort(tri[:, :, 2].mean(axis=1), kind="stable")  # far (small z) first
    ax.add_collection(PolyCollection(tri[order, :, :2], facecolors=rgb[order], edgecolors=rgb[order],
                                     linewidths=0.15))
    for faces, color in highlight:
        faces = np.flatnonzero(faces)
        if len(faces):
            ax.add_collection(PolyCollection(tri[faces, :, :2], facecolors=color, edgecolors=color,
                                             linewidths=0.6, alpha=0.55))
    limits = view_limits(V, R=R) if scale is None else scale
    ax.set_xlim(*limits[0])
    ax.set_ylim(*limits[1])
    ax.set_aspect("equal")
    ax.set_axis_off()


def view_limits(*meshes, R, margin=0.03):
    """Axis limits that show every mesh of ``meshes`` ((n, 3) float each) through camera ``R``, (2, 2) float."""
    P = np.concatenate([V @ R[:2].T for V in meshes])
    lo, hi = P.min(axis=0), P.max(axis=0)
    pad = margin * (hi - lo).max()
    return np.stack([lo - pad, hi + pad], axis=1)


def face_values(values, F):
    """Mean of per-vertex ``values`` (n,) over each face's corners, (m,) float."""
    return np.asarray(values)[F].mean(axis=1)


def heat_colors(values, cmap, vmax):
    """RGB per entry of ``values`` under ``cmap`` on [0, vmax], and the Normalize used, ((k, 3) float, Normalize)."""
    norm = Normalize(vmin=0.0, vmax=vmax if vmax > 0 else 1.0)
    return cmap(norm(values))[:, :3], norm
