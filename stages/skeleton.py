"""Stage skeleton: the skeletal mesh of the reference (S1 §2: medial-ball centres S and radii R), once per library.

The medial repair (stage repair_medial) carries these balls into every target pose. See
``posefix.skeletal.skeletal_mesh``.
"""

import posefix  # noqa: F401  (runtime defaults before numpy)

import numpy as np

from posefix.pipeline.artifacts import write_artifact
from posefix.pipeline.cli import library_defaults, run_stage, stage_parser
from posefix.pipeline.errors import InputError
from posefix.pipeline.library import read_reference
from posefix.pipeline.timings import Timings
from posefix.skeletal.skeletal_mesh import skeletal_mesh

DOCS = {
    "S": ("length", "skeletal mesh vertices (medial-ball centres), (n, 3) float64"),
    "R": ("length", "medial-ball radii |x - s|, (n,) float64"),
    "source": ("label", "which method gave each centre (see the stage log), (n,) int8"),
    "bad": ("bool", "centres still outside the surface or crossing it, (n,) bool"),
}


def build_parser():
    parser = stage_parser("skeleton", __doc__)
    defaults = library_defaults(skeletal_mesh)
    parser.add_argument("--reference", required=True, help="reference mesh (.obj/.ply/.off, optionally .gz)")
    parser.add_argument("--out", required=True, help="skeleton.h5 to write")
    parser.add_argument("--medial", choices=("poles", "shrinking_ball", "auto"), default=defaults["medial"],
                        help="medial-ball centres: Voronoi poles (S1), shrinking balls, or poles, bad ones replaced")
    parser.add_argument("--tol", type=float, default=defaults["tol"],
                        help="a ball crossing the surface by more than tol x its radius counts as bad")
    parser.add_argument("--smooth-iters", type=int, default=defaults["smooth_iters"],
                        help="iterations of the gated bi-Laplacian flow on the skeletal mesh (S1 §2)")
    parser.add_argument("--smooth-step", type=float, default=defaults["smooth_step"], help="step of that flow")
    return parser


def main(args, log):
    timings = Timings()
    with timings.step("read"):
        V, F = read_reference(args.reference)
    with timings.step("skeleton"):
        skeleton = skeletal_mesh(V, F, medial=args.medial, tol=args.tol, smooth_iters=args.smooth_iters,
                                 smooth_step=args.smooth_step)
    missing = int((~np.isfinite(skeleton.S).all(axis=1)).sum())
    if missing:
        raise InputError(args.reference, f"no medial ball for {missing} vertices with --medial {args.medial}; "
                                         "use auto")
    log.info("skeletal mesh of %d vertices: %d bad centres", len(V), int(skeleton.bad.sum()))
    datasets = {"S": skeleton.S, "R": skeleton.R, "source": np.asarray(skeleton.source, dtype=np.int8),
                "bad": skeleton.bad}
    params = {k: v for k, v in vars(args).items() if k not in ("log", "out", "threads")}
    metrics = {k: v for k, v in skeleton.stats.items() if np.isscalar(v)}
    write_artifact(args.out, "skeleton", datasets, params=params, inputs=[args.reference], timings=timings,
                   metrics=metrics, docs=DOCS)


if __name__ == "__main__":
    run_stage(build_parser(), main)
