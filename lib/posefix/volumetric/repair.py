"""The volumetric repair, compared beside space-time: the free region of a target rebuilt by the volumetric editor (S4 §2).

S0 keeps the vertices of ``V_C`` (stage classify: away from the target's self-intersections) and replaces
the rest. Here the ``V_C`` vertices become soft point handles of the reference's coarse tet mesh at their
target positions (S4 §2.3.1: a fixed combination of the vertices of the tet that holds them). S4's
iterations pose the tets as rigidly as the handles allow, so the free region, which has no handle, takes
the reference's shape turned with its surroundings: a fold that pushed one part into another opens up
as far as the volume resists it. S4's smooth transfer (§2.4) gives the surface. The coarse tets cannot
follow ``V_C`` exactly; that residual is spread harmonically over the free vertices, so ``V_C`` is
reproduced exactly and the surface stays continuous.

A fold is often held in place by the ``V_C`` vertices right next to it. The free region is therefore grown
by rings of neighbours (0, 1, 2, 4, ... ``max_rings``) until the filled pose has no new self-intersection
(S0's *new*: not intersecting in the reference); on lion-01, 336 new intersecting faces become 198 with the
free region of ``V_C`` as it is and 6 with 4 more rings.
"""

import logging
import time
from dataclasses import dataclass

import numpy as np

from posefix.mesh.geometry import bbox_diagonal
from posefix.mesh.harmonic import harmonic_extension
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.mesh.topology import grow_rings, vertex_adjacency
from posefix.volumetric.editor import PointHandles, VolumetricEditor
from posefix.volumetric.transfer import transfer_matrix

log = logging.getLogger(__name__)


@dataclass
class VolumetricResult:
    """Outcome of :meth:`VolumetricRepair.repair`.

    Attributes
    ----------
    X : (n, 3) float
        The repaired surface: the target on ``V_C``, the filled free region elsewhere.
    tets : (k, 3) float
        The posed tet-mesh vertices.
    shear : (iterations + 1,) float
        Volume-weighted mean ``|T_j - R_j|`` after every solve (:class:`~posefix.volumetric.editor.EditResult`).
    residual : float
        Largest distance of a kept vertex from its target before the residual is spread (model units).
    free : (n,) bool
        The vertices filled: ``~V_C`` grown by ``rings`` rings.
    rings : int
    faces : (m,) bool
        Intersecting faces of ``X``.
    new_faces : (m,) bool
        New intersecting faces of ``X`` (intersecting, and not in the reference).
    target_faces : int
        New intersecting faces of the target.
    seconds : float
    """

    X: np.ndarray
    tets: np.ndarray
    shear: np.ndarray
    residual: float
    free: np.ndarray
    rings: int
    faces: np.ndarray
    new_faces: np.ndarray
    target_faces: int
    seconds: float


class VolumetricRepair:
    """Fill the free region of targets with S4's editor on the reference's tet mesh; precomputes the transfer.

    Parameters
    ----------
    V : (n, 3) float
        The reference surface; ``F`` (m, 3) int its faces.
    X : (k, 3) float
        Its tet mesh (:func:`~posefix.volumetric.tet_mesh.tet_mesh`); ``T`` (t, 4) int the tets.
    radius : float, optional
        Support of the transfer (model units); default 5 % of the bbox diagonal (S4).

    Examples
    --------
    >>> fill = VolumetricRepair(V, F, *tet_mesh(V, F))              # doctest: +SKIP
    >>> result = fill.repair(target, constrained=mask)            # doctest: +SKIP
    """

    def __init__(self, V, F, X, T, radius=None):
        self.V, self.F, self.X, self.T = V, F, X, T
        self.transfer = transfer_matrix(X, T, V, 0.05 * bbox_diagonal(V) if radius is None else radius)
        self.adjacency = vertex_adjacency(F, len(V))
        self.reference_faces = intersecting_faces(self_intersecting_pairs(V, F), len(F))

    def intersecting(self, X):
        """Faces of ``X`` in an intersecting pair, (m,) bool; *new* (S0's) are those ``& ~reference_faces``."""
        return intersecting_faces(self_intersecting_pairs(X, self.F), len(self.F))

    def fill(self, target, free, iterations=10, point_weight=10.0):
        """The target (n, 3) with the ``free`` vertices (n,) bool filled: (surface (n, 3), EditResult, residual).

        ``iterations``: S4 iterations from the identity rotations; ``point_weight``: weight of the kept
        vertices' point handles relative to the mean diagonal of the tet Laplacian
        (:class:`~posefix.volumetric.editor.VolumetricEditor`).
        """
        kept = ~np.asarray(free, dtype=bool)
        if not kept.any():
            raise ValueError("every vertex is free: nothing holds the tets")
        editor = VolumetricEditor(self.X, self.T, np.zeros(0, dtype=np.int64), points=PointHandles(self.V[kept], point_weight))
        edit = editor.solve(np.zeros((0, 3)), iterations, point_targets=target[kept])
        surface = self.transfer @ edit.X
        offset = np.where(kept[:, None], target - surface, 0.0)
        X = surface + harmonic_extension(self.adjacency, offset, kept)
        X[kept] = target[kept]  # exactly, not up to rounding
        return X, edit, float(np.linalg.norm(offset, axis=1).max())

    def repair(self, target, constrained, iterations=10, point_weight=10.0, max_rings=16, max_free=0.5):
        """Fill the free vertices of ``target`` (n, 3), ``~constrained`` ((n,) bool: ``V_C``), grown by 0, 1, 2,
        4, ... ``max_rings`` rings until no new intersection remains (else the try with the fewest):
        a :class:`VolumetricResult`. A grown region of more than ``max_free`` of the vertices is not tried (the
        fill would undo the pose, not repair it). ``iterations``, ``point_weight``: see :meth:`fill`."""
        start = time.perf_counter()
        target_faces = int((self.intersecting(target) & ~self.reference_faces).sum())
        best = None
        for rings in [0] + [2 ** k for k in range(int(max_rings).bit_length())]:
            free = grow_rings(~np.asarray(constrained, dtype=bool), self.adjacency, rings)
            if best is not None and free.mean() > max_free:
                break
            X, edit, residual = self.fill(target, free, iterations, point_weight)
            faces = self.intersecting(X)
            new = faces & ~self.reference_faces
            log.info("%d rings: %d free vertices, %d new intersecting faces (target %d), shear %.3g -> %.3g",
                     rings, free.sum(), new.sum(), target_faces, edit.shear[0], edit.shear[-1])
            if best is None or new.sum() < best[-1].sum():
                best = (X, edit, residual, free, rings, faces, new)
            if not new.any():
                break
        X, edit, residual, free, rings, faces, new = best
        return VolumetricResult(X, edit.X, edit.shear, residual, free, rings, faces, new, target_faces,
                          time.perf_counter() - start)
