"""The reference's skeletal mesh in the stages (skeleton, skeletal_pose): its options and the checked build."""

import numpy as np

from posefix.workflow.cli import library_defaults
from posefix.io.errors import InputError
from posefix.medial.skeletal_mesh import skeletal_mesh


def add_skeleton_options(parser):
    """``--medial``, ``--tol``, ``--smooth-iters``, ``--smooth-step`` with :func:`skeletal_mesh`'s defaults."""
    defaults = library_defaults(skeletal_mesh)
    parser.add_argument("--medial", choices=("poles", "shrinking_ball", "auto"), default=defaults["medial"],
                        help="medial-ball centres: inner Voronoi poles (the paper's), shrinking balls, or poles, bad ones replaced")
    parser.add_argument("--tol", type=float, default=defaults["tol"],
                        help="a ball crossing the surface by more than tol x its radius counts as bad")
    parser.add_argument("--smooth-iters", type=int, default=defaults["smooth_iters"],
                        help="iterations of the gated bi-Laplacian flow on the skeletal mesh")
    parser.add_argument("--smooth-step", type=float, default=defaults["smooth_step"], help="step of that flow")


def reference_skeleton(path, V, F, args):
    """:func:`skeletal_mesh` of the mesh read from ``path`` with the options of :func:`add_skeleton_options`;
    :class:`InputError` naming ``path`` when a vertex gets no medial ball."""
    skeleton = skeletal_mesh(V, F, medial=args.medial, tol=args.tol, smooth_iters=args.smooth_iters,
                             smooth_step=args.smooth_step)
    missing = int((~np.isfinite(skeleton.S).all(axis=1)).sum())
    if missing:
        raise InputError(path, f"no medial ball for {missing} vertices with --medial {args.medial}; use auto")
    return skeleton
