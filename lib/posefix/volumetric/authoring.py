"""Pose authoring with S4's editor: handles moved per pose, the surface carried by S4's smooth transfer (§2.4).

A handle is a region of tets (all vertices handles, its orientation imposed, S4 §2.3.1); a move turns it
about its rest centroid and translates it. Large turns are reached in ``frames`` steps, each warm-started
from the last (S4's interaction loop), so that the rotation interpolation only averages small changes.
"""

import logging
import time
from dataclasses import dataclass

import numpy as np

from posefix.mesh.rotations import rotation_exp
from posefix.volumetric.editor import EditResult, PointHandles, VolumetricEditor
from posefix.mesh.geometry import bbox_diagonal
from posefix.volumetric.transfer import transfer_matrix

log = logging.getLogger(__name__)


def region_tets(X, T, box):
    """Tets whose four vertices lie in the axis-aligned ``box`` (2, 3) [min corner, max corner], (k,) int64."""
    inside = np.all((X >= box[0]) & (X <= box[1]), axis=1)
    return np.flatnonzero(inside[T].all(axis=1))


@dataclass
class AuthoredPose:
    """A pose: the surface ``positions`` (n, 3), the tet mesh's ``edit`` (:class:`EditResult`) and seconds."""

    positions: np.ndarray
    edit: EditResult
    seconds: float


class VolumetricPoser:
    """Pose a surface mesh ``V`` (n, 3) through its tet mesh ``(X, T)`` by region handles.

    Parameters
    ----------
    V : (n, 3) float
        The surface (the reference), embedded in the tets.
    X : (k, 3) float
        Tet-mesh vertices; ``T`` (t, 4) int its tets.
    handles : dict of str -> (h,) int
        Handle regions as tet ids (disjoint vertex sets).
    rigid : dict of str -> (r,) int, optional
        Rigid regions as tet ids.
    points : dict of str -> (p, 3) float, optional
        Point handles (rest positions inside or near the tets), a group per name.
    radius : float, optional
        Support of the transfer (:func:`~posefix.volumetric.transfer.transfer_matrix`, model units);
        default 5 % of the surface's bbox diagonal (S4).
    """

    def __init__(self, V, X, T, handles, rigid=None, points=None, radius=None):
        self.V, self.X, self.T = V, X, T
        self.names = list(handles)
        self.regions = [np.asarray(handles[n]) for n in self.names]
        self.region_vertices = [np.unique(T[r]) for r in self.regions]
        self.points = {n: np.asarray(p, dtype=float).reshape(-1, 3) for n, p in (points or {}).items()}
        vertices = np.concatenate(self.region_vertices) if self.regions else np.zeros(0, dtype=np.int64)
        if len(np.unique(vertices)) < len(vertices):
            raise ValueError("handle regions share vertices")
        self.editor = VolumetricEditor(X, T, vertices, rigid=list((rigid or {}).values()), regions=self.regions,
                                       points=PointHandles(np.concatenate(list(self.points.values())))
                                       if self.points else None)
        self.transfer = transfer_matrix(X, T, V, 0.05 * bbox_diagonal(V) if radius is None else radius)

    def targets(self, moves, fraction=1.0):
        """Targets of the region handles' vertices (h, 3), their rotations (r, 3, 3) and the point handles'
        targets (p, 3) or None, for ``moves`` {name: (rotation vector, translation)} scaled by ``fraction``."""
        groups = [(n, self.X[v]) for n, v in zip(self.names, self.region_vertices)] + list(self.points.items())
        moved, rotations = [], []
        for name, rest in groups:
            omega, shift = moves.get(name, (np.zeros(3), np.zeros(3)))
            R = rotation_exp(fraction * np.asarray(omega)[None])[0]
            centre = rest.mean(axis=0)
            moved.append(centre + (rest - centre) @ R.T + fraction * np.asarray(shift))
            rotations.append(R)
        regions = len(self.names)
        vertex_targets = np.concatenate(moved[:regions]) if regions else np.zeros((0, 3))
        point_targets = np.concatenate(moved[regions:]) if self.points else None
        return vertex_targets, (np.stack(rotations[:regions]) if regions else None), point_targets

    def pose(self, moves, iterations=10, frames=4):
        """The surface posed by ``moves`` (see :meth:`targets`), reached in ``frames`` warm-started steps."""
        start = time.perf_counter()
        rotations = None
        for k in range(1, frames + 1):
            targets, region_rotations, point_targets = self.targets(moves, k / frames)
            edit = self.editor.solve(targets, iterations, warm_start=rotations, region_rotations=region_rotations,
                                     point_targets=point_targets)
            rotations = edit.rotations
        positions = self.transfer @ edit.X
        seconds = time.perf_counter() - start
        log.debug("posed in %d frames of %d iterations: shear %.3g, %.2f s", frames, iterations, edit.shear[-1],
                  seconds)
        return AuthoredPose(positions, edit, seconds)
