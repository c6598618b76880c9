"""Stage repair_medial: the medial repair of one pose (medial balls and their flow, S1 §2-4), compared beside space-time.

Carries the reference's medial balls (stage skeleton) into the target, rebuilds the damaged region on
them and runs the medial-ball flow (S1 §4) until no new self-intersection remains (intersections the reference
has too do not count) or ``--max-iters``. See ``posefix.medial.repair``.
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

from posefix.mesh.geometry import bbox_diagonal
from posefix.io.artifacts import read_artifact, write_artifact
from posefix.workflow.cli import run_stage, stage_parser
from posefix.workflow.settings import add_settings_options
from posefix.io.errors import InputError
from posefix.io.library import read_welded_pair
from posefix.workflow.timings import Timings
from posefix.medial.repair import MedialRepair
from posefix.workflow.stage_settings import MedialRepairSettings

DOCS = {
    "start": ("length", "the target pose, (n, 3) float64"),
    "repaired": ("length", "the medial-repaired pose, (n, 3) float64"),
    "intersecting": ("faces", "new intersecting faces (not intersecting in the reference) before every flow iteration (0: the rebuilt start) and after the last, (k+1,) int64"),
    "error": ("length", "the flow's error sum_i |f(x_i)| (S1 §4) at the same moments, (k+1,) float64"),
    "step_seconds": ("s", "seconds of each flow step, (k,) float64"),
    "skeleton": ("length", "the deformed skeletal mesh (ball centres; radii are the reference's), (n, 3) float64"),
    "free": ("bool", "the damaged region rebuilt on the carried balls, (n,) bool"),
}


def build_parser():
    parser = stage_parser("repair_medial", __doc__)
    parser.add_argument("--reference", required=True, help="reference mesh file")
    parser.add_argument("--target", required=True, help="target pose file")
    parser.add_argument("--skeleton", required=True, help="skeleton.h5 of the reference")
    parser.add_argument("--out", required=True, help="medial.h5 to write")
    add_settings_options(parser, MedialRepairSettings, "medial repair (config medial.repair)")
    return parser


def main(args, log):
    timings = Timings()
    if args.margin < 0 or args.tau <= 0 or args.neighbours < 1 or args.max_reach < 1 or args.max_iters < 0:
        raise InputError("arguments", "need --margin >= 0, --tau > 0, --neighbours >= 1, --max-reach >= 1, "
                                      "--max-iters >= 0")
    with timings.step("read"):
        V, X, F, _ = read_welded_pair(args.reference, args.target)
        skeleton, _ = read_artifact(args.skeleton, "skeleton", ["S"])
    if skeleton["S"].shape != V.shape:
        raise InputError(args.skeleton, f"{len(skeleton['S'])} centres for a reference of {len(V)} vertices")
    with timings.step("prepare"):
        repair = MedialRepair(V, F, skeleton["S"], args.margin * bbox_diagonal(V), args.tau, args.neighbours,
                              args.max_reach)
    with timings.step("repair"):
        result = repair.repair(X, args.max_iters)
    flow = result.flow
    final = int(flow.intersecting[flow.best])
    log.info("new intersecting faces: target %d, rebuilt start %d (%d vertices, reach %g radii), repaired %d "
             "(%d flow iterations, best %d), %.2f s", result.target_faces, result.start_faces, result.free.sum(),
             result.reach, final, flow.iterations, flow.best, result.seconds)
    datasets = {"start": X, "repaired": result.X, "intersecting": flow.intersecting, "error": flow.error,
                "step_seconds": flow.step_seconds, "skeleton": result.S_d, "free": result.free}
    metrics = {"iterations": flow.iterations, "best": flow.best, "seconds": result.seconds, "reach": result.reach,
               "free_vertices": int(result.free.sum()), "intersecting_faces_target": result.target_faces,
               "intersecting_faces_start": result.start_faces,
               "intersecting_faces_repaired": int(repair.all_faces(result.X).sum()),
               "intersecting_faces_repaired_new": final}
    params = {k: v for k, v in vars(args).items() if k not in ("log", "out", "threads")}
    write_artifact(args.out, "repair_medial", datasets, params=params,
                   inputs=[args.reference, args.target, args.skeleton], timings=timings, metrics=metrics, docs=DOCS)


if __name__ == "__main__":
    run_stage(build_parser(), main)
