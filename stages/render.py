"""Stage render: the report figures of one pose (PNG, offscreen).

Writes into ``--out``: ``renders.png`` (target vs repaired, and every ``--repair`` beside
them, intersecting and distorted faces highlighted),
``deviation.png`` (deviation heat map on the repaired pose with a colour bar, fallback regions),
``classification.png`` (intersecting faces per key frame before and after, ``V_C`` on the
reference), ``fit.png`` (fit history: error, condition, seconds per iteration) and
``timings.png`` (wall seconds per stage from the Snakemake benchmark files). The camera is fixed by
the reference (the same for every pose of a library). Figures are built in ``posefix.report.figures``.
"""

import json
from pathlib import Path

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

from posefix.mesh.distortion import distorted_faces
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.io.artifacts import read_artifact, repaired_poses
from posefix.workflow.cli import add_repair_option, run_stage, stage_parser
from posefix.workflow.stage_settings import SummarySettings
from posefix.io.files import write_figure
from posefix.workflow.timings import Timings, benchmark_seconds
from posefix.report import figures
from posefix.report.contents import POSE_FIGURES, SPACETIME, TIMED_STAGES
from posefix.report.rasterizer import camera
from posefix.spacetime.classification import split_frames

HISTORY = ("centers", "max_error", "rms_error", "condition", "seconds_evaluate", "seconds_select", "seconds_update")


def build_parser():
    parser = stage_parser("render", __doc__, [(SummarySettings, "distortion (config summary)")],
                          keyframes="keyframes.h5 of the pose (reference, target, faces)",
                          classify="classify.h5 of the pose (V_C, pairs per key frame)",
                          fit="fit.h5 of the pose (history)",
                          verify="verify.h5 of the pose (repaired pose, deviation)",
                          benchmarks="folder of the pose's Snakemake benchmark files",
                          pose="pose name (figure titles)", out="folder to write the PNG files into")
    add_repair_option(parser, "draw it beside the repaired pose in renders.png")
    return parser


def main(args, log):
    timings = Timings()
    with timings.step("read"):
        kf, _ = read_artifact(args.keyframes, "keyframes", ["reference", "target", "faces"])
        cl, _ = read_artifact(args.classify, "classify", ["mask", "pairs", "pair_offsets", "intersecting_faces"])
        fi, fattrs = read_artifact(args.fit, "fit", [f"history/{k}" for k in HISTORY])
        ve, _ = read_artifact(args.verify, "verify", ["repaired", "deviation", "replaced", "pairs", "new_faces"])
        compared = repaired_poses(args.repair)
    V_ref, V_tgt, F = kf["reference"], kf["target"], kf["faces"]
    m = len(F)
    frame_pairs = split_frames(cl["pairs"], cl["pair_offsets"])
    reference_faces, target_faces = intersecting_faces(frame_pairs[0], m), intersecting_faces(frame_pairs[-1], m)
    repaired_faces = intersecting_faces(ve["pairs"], m)
    with timings.step("intersections"):
        repairs = {name: (X, intersecting_faces(self_intersecting_pairs(X, F), m)) for name, X in compared.items()}
        distorted = [distorted_faces(X, [V_tgt, V_ref], F, args.distortion_limit)
                     for X in [ve["repaired"], *compared.values()]]
    R = camera(V_ref)
    made = {}
    with timings.step("figures"):
        poses = {"target": (V_tgt, target_faces), SPACETIME if repairs else "repaired": (ve["repaired"],
                                                                                             repaired_faces)}
        made["renders"] = figures.renders(F, R, poses | repairs, reference_faces, args.pose, distorted)
        made["deviation"] = figures.deviation_map(ve["repaired"], F, R, ve["deviation"], ve["replaced"],
                                                  title=args.pose)
        made["classification"] = figures.classification(
            V_ref, F, R, cl["mask"].astype(bool), cl["intersecting_faces"], int(repaired_faces.sum()),
            int(ve["new_faces"].sum()), title=args.pose)
        made["fit"] = figures.fit_history({k: fi[f"history/{k}"] for k in HISTORY},
                                          float(fattrs["metrics"]["bbox_diagonal"]),
                                          json.loads(fattrs["config"])["eps_rel"], title=args.pose)
        made["timings"] = figures.timings({s: benchmark_seconds(args.benchmarks, s) for s in TIMED_STAGES},
                                          title=args.pose)
    with timings.step("write"):
        for name in POSE_FIGURES:
            write_figure(Path(args.out) / f"{name}.png", made[name])
    log.info("wrote %d figures into %s", len(POSE_FIGURES), args.out)


if __name__ == "__main__":
    run_stage(build_parser(), main)
