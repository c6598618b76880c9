"""S4's marker animation (§3.2): a character driven by motion-capture marker tracks.

Every marker is attached once, at its rest position, to the tet mesh as a point handle (S4 §2.3.1: a fixed
linear combination of the vertices of the tet that holds it, also slightly outside the surface). Every
frame is one editor solve with the handles at that frame's marker positions, warm-started from the
previous frame's rotations with a few S4 iterations (the first frame from the identity, with more), and
the surface follows by S4's transfer (§2.4).
"""

import logging
import time
from dataclasses import dataclass

import numpy as np

from posefix.mesh.geometry import bbox_diagonal
from posefix.volumetric.editor import PointHandles, VolumetricEditor
from posefix.volumetric.transfer import transfer_matrix

log = logging.getLogger(__name__)


@dataclass
class MarkerAnimation:
    """Outcome of :meth:`MarkerAnimator.animate` over ``f`` frames of ``p`` markers.

    Attributes
    ----------
    frames : (f, n, 3) float
        The surface in every frame.
    tets : (f, k, 3) float
        The tet-mesh vertices in every frame.
    residuals : (f, p) float
        Distance of every marker's place on the animated surface (its rest position carried by the
        transfer) from its captured position, model units.
    shear : (f,) float
        Volume-weighted mean ``|T_j - R_j|`` of the tets after each frame's last solve.
    seconds : (f,) float
        Wall seconds per frame (solves and transfer).
    """

    frames: np.ndarray
    tets: np.ndarray
    residuals: np.ndarray
    shear: np.ndarray
    seconds: np.ndarray


class MarkerAnimator:
    """Animate a surface ``V`` (n, 3) by markers, through its tet mesh ``(X, T)``; factorizes once.

    Parameters
    ----------
    V : (n, 3) float
        The surface at rest (the reference).
    X : (k, 3) float
        Tet-mesh vertices at rest; ``T`` (t, 4) int the tets.
    markers : (p, 3) float
        Rest positions of the markers, on or near the surface.
    rigid : sequence of (r,) int, optional
        Rigid regions as tet ids (:class:`~posefix.volumetric.editor.VolumetricEditor`).
    radius : float, optional
        Support of the transfer (model units); default 5 % of the bbox diagonal (S4).
    point_weight : float, optional
        Soft markers (least squares, see the editor); default exact (S4).

    Examples
    --------
    >>> animator = MarkerAnimator(V, X, T, markers=V[ids])        # doctest: +SKIP
    >>> result = animator.animate(tracks)                         # tracks (f, p, 3)  # doctest: +SKIP
    """

    def __init__(self, V, X, T, markers, rigid=(), radius=None, point_weight=None):
        markers = np.asarray(markers, dtype=float).reshape(-1, 3)
        radius = 0.05 * bbox_diagonal(V) if radius is None else radius
        self.editor = VolumetricEditor(X, T, np.zeros(0, dtype=np.int64), rigid=rigid,
                                       points=PointHandles(markers, point_weight))
        self.transfer = transfer_matrix(X, T, V, radius)
        self.marker_transfer = transfer_matrix(X, T, markers, radius)

    def animate(self, tracks, iterations=3, first_iterations=10):
        """The surface in every frame of ``tracks`` (f, p, 3): a :class:`MarkerAnimation`.

        ``iterations``: S4 iterations per frame, warm-started from the previous frame's rotations;
        ``first_iterations``: for the first frame, from the identity (0 and 0: the linear tet Laplacian alone).
        """
        tracks = np.asarray(tracks, dtype=float)
        frames, tets, residuals, shear, seconds = [], [], [], [], []
        rotations = None
        no_handles = np.zeros((0, 3))
        for k, targets in enumerate(tracks):
            start = time.perf_counter()
            edit = self.editor.solve(no_handles, first_iterations if k == 0 else iterations, warm_start=rotations,
                                     point_targets=targets)
            rotations = edit.rotations
            frames.append(self.transfer @ edit.X)
            tets.append(edit.X)
            residuals.append(np.linalg.norm(self.marker_transfer @ edit.X - targets, axis=1))
            shear.append(edit.shear[-1])
            seconds.append(time.perf_counter() - start)
        result = MarkerAnimation(np.stack(frames), np.stack(tets), np.stack(residuals), np.array(shear),
                                 np.array(seconds))
        log.debug("%d frames: marker residual max %.3g, %.3f s per frame", len(tracks), result.residuals.max(),
                  result.seconds.mean())
        return result
