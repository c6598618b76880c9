"""Stage skeleton: the skeletal mesh of the reference (S1 §2: medial-ball centres S and radii R), once per library.

The medial repair (stage repair_medial) carries these balls into every target pose. See
``posefix.medial.skeletal_mesh``.
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

import numpy as np

from posefix.io.artifacts import write_artifact
from posefix.workflow.cli import dataset_docs, run_stage, stage_parser
from posefix.io.library import read_welded_reference
from posefix.workflow.skeleton_options import add_skeleton_options, reference_skeleton
from posefix.workflow.timings import Timings


def build_parser():
    parser = stage_parser("skeleton", __doc__, reference="reference mesh (.obj/.ply/.off, optionally .gz)",
                          out="skeleton.h5 to write")
    add_skeleton_options(parser)
    return parser


def main(args, log):
    timings = Timings()
    with timings.step("read"):
        V, F, _ = read_welded_reference(args.reference)
    with timings.step("skeleton"):
        skeleton = reference_skeleton(args.reference, V, F, args)
    log.info("skeletal mesh of %d vertices: %d bad centres", len(V), int(skeleton.bad.sum()))
    datasets = {"S": skeleton.S, "R": skeleton.R, "source": np.asarray(skeleton.source, dtype=np.int8),
                "bad": skeleton.bad}
    params = {k: v for k, v in vars(args).items() if k not in ("log", "out", "threads")}
    metrics = {k: v for k, v in skeleton.stats.items() if np.isscalar(v)}
    write_artifact(args.out, "skeleton", datasets, params=params, inputs=[args.reference], timings=timings,
                   metrics=metrics, docs=dataset_docs("skeleton"))


if __name__ == "__main__":
    run_stage(build_parser(), main)
