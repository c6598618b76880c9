"""Stage repair_medial: the medial repair of one pose (medial balls and their flow, S1 §2-4), compared beside space-time.

Carries the reference's medial balls (stage skeleton) into the target, rebuilds the damaged region on
them and runs the medial-ball flow (S1 §4) until no new self-intersection remains (intersections the reference
has too do not count) or ``--max-iters``. See ``posefix.medial.repair``.
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

from posefix.mesh.geometry import bbox_diagonal
from posefix.io.artifacts import read_artifact, write_artifact
from posefix.workflow.cli import dataset_docs, run_stage, stage_parser
from posefix.io.errors import InputError
from posefix.io.library import read_welded_pair
from posefix.workflow.timings import Timings
from posefix.medial.repair import MedialRepair
from posefix.workflow.stage_settings import MedialRepairSettings


def build_parser():
    return stage_parser("repair_medial", __doc__, [(MedialRepairSettings, "medial repair (config medial.repair)")],
                        reference="reference mesh file", target="target pose file",
                        skeleton="skeleton.h5 of the reference", out="medial.h5 to write")


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
    datasets = {"repaired": result.X, "intersecting": flow.intersecting, "error": flow.error,
                "step_seconds": flow.step_seconds, "skeleton": result.S_d, "free": result.free}
    metrics = {"iterations": flow.iterations, "best": flow.best, "seconds": result.seconds, "reach": result.reach,
               "free_vertices": int(result.free.sum()), "intersecting_faces_target": result.target_faces,
               "intersecting_faces_start": result.start_faces,
               "intersecting_faces_repaired": int(repair.all_faces(result.X).sum()),
               "intersecting_faces_repaired_new": final}
    params = {k: v for k, v in vars(args).items() if k not in ("log", "out", "threads")}
    write_artifact(args.out, "repair_medial", datasets, params=params,
                   inputs=[args.reference, args.target, args.skeleton], timings=timings, metrics=metrics, docs=dataset_docs("repair_medial"))


if __name__ == "__main__":
    run_stage(build_parser(), main)
