"""The reference's skeletal mesh in the stages (skeleton, skeletal_pose): its options and the checked build."""

import numpy as np

from posefix.io.errors import InputError
from posefix.medial.skeletal_mesh import skeletal_mesh
from posefix.workflow.settings import add_settings_options
from posefix.workflow.stage_settings import SkeletonSettings


def add_skeleton_options(parser):
    """``--medial``, ``--tol``, ``--smooth-iters``, ``--smooth-step``: :class:`SkeletonSettings`' options."""
    add_settings_options(parser, SkeletonSettings, "skeletal mesh (config medial.skeleton)")


def reference_skeleton(path, V, F, args):
    """:func:`skeletal_mesh` of the mesh read from ``path`` with the options of :func:`add_skeleton_options`;
    :class:`InputError` naming ``path`` when a vertex gets no medial ball."""
    skeleton = skeletal_mesh(V, F, medial=args.medial, tol=args.tol, smooth_iters=args.smooth_iters,
                             smooth_step=args.smooth_step)
    missing = int((~np.isfinite(skeleton.S).all(axis=1)).sum())
    if missing:
        raise InputError(path, f"no medial ball for {missing} vertices with --medial {args.medial}; use auto")
    return skeleton
