"""Skeleton-driven pose authoring (S1 Fig. 1): a rig poses the skeletal mesh, the mesh follows.

Three variants per pose, the comparison of S1 Fig. 12-13:

- ``ssd``: linear blend skinning of the mesh itself (the classic skeletal subspace deformation);
- ``variational``: skinning of the skeletal mesh, then the reconstruction of S1 §3 (Eq. 3-5);
- ``flow``: the variational pose evolved by the medial-ball flow of S1 §4 (Eq. 9-10).
"""

import logging
import time
from dataclasses import dataclass

import numpy as np

from posefix.mesh.rotations import polar_decomposition
from posefix.medial.flow import FlowResult, MedialBallFlow, union_of_balls
from posefix.medial.reconstruction import SkeletalReconstruction
from posefix.medial.rig import blend_skin, blended_linear_maps, bone_transforms, skinning_weights

log = logging.getLogger(__name__)

VARIANTS = ("ssd", "variational", "flow")
"""The authored variants of every pose, in order."""


class SkeletalPoser:
    """Poses a mesh through its skeletal mesh; the weights and ``(I + L)`` are computed once.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    S : (n, 3) float
        The skeletal mesh of ``V`` (:func:`posefix.medial.skeletal_mesh.skeletal_mesh`).
    rig : Rig
    falloff : float
        Skinning blend length relative to the mean bone length (:func:`~posefix.medial.rig.skinning_weights`).
    min_sine : float
        Skeletal triangles with a smaller corner sine take the rig's blended rotation as frame map.
    min_area : float
        So do those smaller than this x their mesh triangle (a collapsed skeleton, S1 §5).
    """

    def __init__(self, V, F, S, rig, falloff=0.2, min_sine=0.05, min_area=0.1):
        self.V, self.F, self.S, self.rig, self.min_sine = V, F, S, rig, min_sine
        self.weights_S = skinning_weights(rig, S, falloff)
        self.weights_V = skinning_weights(rig, V, falloff)
        self.reconstruction = SkeletalReconstruction(V, F, S, min_area)

    def ssd(self, pose):
        """Linear blend skinning of the mesh: (n, 3) float."""
        return blend_skin(self.V, self.weights_V, *bone_transforms(self.rig, pose))

    def skeleton(self, pose):
        """The deformed skeletal mesh ``S_d`` (n, 3) and the fallback frame maps (m, 3, 3) of its faces.

        The fallback of a face is the rotation (polar factor) of the skinning's linear part averaged over
        its corners.
        """
        A, t = bone_transforms(self.rig, pose)
        linear = blended_linear_maps(self.weights_S, A)
        fallback, _ = polar_decomposition(linear[self.F].mean(axis=1))
        return blend_skin(self.S, self.weights_S, A, t), fallback

    def variational(self, pose):
        """The reconstruction of S1 §3 for ``pose``: (X (n, 3), S_d (n, 3))."""
        S_d, fallback = self.skeleton(pose)
        return self.reconstruction.reconstruct(S_d, fallback, self.min_sine), S_d

    def author(self, pose, margin, tau=0.5, neighbours=64, max_iters=50):
        """All :data:`VARIANTS` of ``pose``.

        Parameters
        ----------
        pose : RigPose
        margin : float
            The flow's margin (model units; see :mod:`posefix.medial.flow`).
        tau : float
            The flow's step size.
        neighbours : int
            The flow's candidate balls per vertex at most (0: all, S1).
        max_iters : int
            The flow's iterations at most.

        Returns
        -------
        AuthoredPose
        """
        t0 = time.perf_counter()
        X_ssd = self.ssd(pose)
        t1 = time.perf_counter()
        X_var, S_d = self.variational(pose)
        t2 = time.perf_counter()
        flow = MedialBallFlow(self.reconstruction, S_d, margin, tau, neighbours).run(X_var, max_iters)
        seconds = {"ssd": t1 - t0, "variational": t2 - t1, "flow": time.perf_counter() - t2}
        return AuthoredPose({"ssd": X_ssd, "variational": X_var, "flow": flow.X}, S_d, flow, seconds)


@dataclass(frozen=True)
class AuthoredPose:
    """The variants of one authored pose.

    Attributes
    ----------
    positions : dict of str -> (n, 3) float
        By variant (:data:`VARIANTS`).
    S_d : (n, 3) float
        The deformed skeletal mesh.
    flow : FlowResult
    seconds : dict of str -> float
        Wall seconds per variant (``flow`` without the reconstruction it starts from).
    """

    positions: dict
    S_d: np.ndarray
    flow: FlowResult
    seconds: dict


def union_error(X, S_d, R):
    """S1 Fig. 13's surface approximation error: ``sum_i |f(x_i)|`` over the union of the balls (model units)."""
    return float(np.abs(union_of_balls(X, S_d, R)).sum())
