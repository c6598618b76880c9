"""Pose authoring with S4's editor: region handles moved per pose, the surface carried by the tet mesh.

A handle is a region of tets (all vertices handles, its orientation imposed, S4 §2.3.1); a move turns it
about its rest centroid and translates it. Large turns are reached in ``frames`` steps, each warm-started
from the last (S4's interaction loop), so that the rotation interpolation only averages small changes.
"""

import logging
import time
from dataclasses import dataclass

import numpy as np

from posefix.mesh.rotations import rotation_exp
from posefix.volumetric.editor import EditResult, VolumetricEditor
from posefix.volumetric.embedding import barycentric_embedding, embedded_points

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
    """

    def __init__(self, V, X, T, handles, rigid=None):
        self.V, self.X, self.T = V, X, T
        self.names = list(handles)
        self.regions = [np.asarray(handles[n]) for n in self.names]
        self.region_vertices = [np.unique(T[r]) for r in self.regions]
        vertices = np.concatenate(self.region_vertices)
        if len(np.unique(vertices)) < len(vertices):
            raise ValueError("handle regions share vertices")
        self.editor = VolumetricEditor(X, T, vertices, rigid=list((rigid or {}).values()), regions=self.regions)
        self.embedding = barycentric_embedding(X, T, V)

    def targets(self, moves, fraction=1.0):
        """Handle targets (h, 3) and region rotations (r, 3, 3) for ``moves`` {name: (rotvec, translation)}."""
        targets, rotations = [], []
        for name, verts in zip(self.names, self.region_vertices):
            omega, shift = moves.get(name, (np.zeros(3), np.zeros(3)))
            R = rotation_exp(fraction * np.asarray(omega)[None])[0]
            centre = self.X[verts].mean(axis=0)
            targets.append(centre + (self.X[verts] - centre) @ R.T + fraction * np.asarray(shift))
            rotations.append(R)
        return np.concatenate(targets), np.stack(rotations)

    def pose(self, moves, iterations=10, frames=4):
        """The surface posed by ``moves`` (see :meth:`targets`), reached in ``frames`` warm-started steps."""
        start = time.perf_counter()
        rotations = None
        for k in range(1, frames + 1):
            targets, region_rotations = self.targets(moves, k / frames)
            edit = self.editor.solve(targets, iterations, warm_start=rotations, region_rotations=region_rotations)
            rotations = edit.rotations
        positions = embedded_points(edit.X, self.T, *self.embedding)
        seconds = time.perf_counter() - start
        log.debug("posed in %d frames of %d iterations: shear %.3g, %.2f s", frames, iterations, edit.shear[-1],
                  seconds)
        return AuthoredPose(positions, edit, seconds)
