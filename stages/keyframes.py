"""Stage keyframes: key frames from the reference to one target pose (S0 §4.1).

Gradient-space interpolation (Xu et al. 2005) with global rigid alignment and rotation-branch
unwrapping; see ``posefix.spacetime.keyframes`` for the method. Writes ``keyframes.h5`` with the K frames at
t = k/(K-1), the two input poses, and per-face rotation diagnostics.
"""

from pathlib import Path

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)
import numpy as np

from posefix.mesh.geometry import bbox_diagonal
from posefix.io.artifacts import write_artifact
from posefix.workflow.cli import run_stage, stage_parser
from posefix.workflow.settings import add_settings_options
from posefix.io.library import read_welded_pair
from posefix.workflow.timings import Timings
from posefix.spacetime import keyframes as kf
from posefix.workflow.stage_settings import KeyframesSettings

DOCS = {
    "t": ("1", "key-frame times in [0, 1], (K,) float64"),
    "frames": ("length", "key-frame vertex positions, (K, n, 3) float64; frames[0] = reference, frames[-1] = target"),
    "faces": ("index", "triangle vertex indices, (m, 3) int64"),
    "reference": ("length", "reference vertex positions, (n, 3) float64"),
    "target": ("length", "target vertex positions, (n, 3) float64"),
    "weld_index": ("index", "vertex (of the n) of every input vertex: n is less than the input's vertex count when the "
                            "reference has vertices split along seams, which are welded (N,) int64"),
    "rotation_angle": ("rad", "per-face rotation angle reference -> aligned target after unwrapping, (m,) float64"),
    "branch_turns": ("1", "per-face number of full turns added by the branch unwrapping, (m,) int64"),
    "global_rotation": ("rad", "rotation vector of the removed global rigid rotation, (3,) float64"),
}


def build_parser():
    parser = stage_parser("keyframes", __doc__)
    parser.add_argument("--reference", required=True, help="reference mesh file")
    parser.add_argument("--target", required=True, help="target pose mesh file")
    parser.add_argument("--out", required=True, help="keyframes.h5 to write")
    add_settings_options(parser, KeyframesSettings, "key frames (config keyframes)")
    return parser


def main(args, log):
    timings = Timings()
    with timings.step("read"):
        V_ref, V_tgt, F, weld = read_welded_pair(args.reference, args.target)
    if weld.split:
        log.info("%d vertices split along seams in the reference: welded to %d for the computation",
                 len(weld.index), len(weld.kept))
    d = bbox_diagonal(V_ref)
    log.info("%s -> %s: %d vertices, %d faces, K = %d", Path(args.reference).name, Path(args.target).name,
             len(V_ref), len(F), args.count)
    with timings.step("prepare"):
        interp = kf.prepare(V_ref, V_tgt, F, align=args.align, unwrap=args.unwrap)
    angle = np.linalg.norm(interp.omega, axis=1)
    log.info("global rotation %.1f deg; per-face rotation median %.1f, max %.1f deg; %d faces unwrapped",
             np.degrees(np.linalg.norm(interp.global_omega)), np.degrees(np.median(angle)),
             np.degrees(angle.max()), np.count_nonzero(interp.turns))
    t = np.linspace(0.0, 1.0, args.count)
    with timings.step("frames"):
        frames = np.stack([kf.frame(interp, ti) for ti in t])
    err0 = np.abs(frames[0] - V_ref).max() / d
    err1 = np.abs(frames[-1] - V_tgt).max() / d
    log.info("endpoint error / bbox diagonal: reference %.1e, target %.1e", err0, err1)
    write_artifact(
        args.out, "keyframes",
        {"t": t, "frames": frames, "faces": F, "reference": V_ref, "target": V_tgt, "weld_index": weld.index,
         "rotation_angle": angle, "branch_turns": interp.turns, "global_rotation": interp.global_omega},
        params={"count": args.count, "align": args.align, "unwrap": args.unwrap},
        inputs=[args.reference, args.target], timings=timings,
        metrics={"vertices": len(V_ref), "input_vertices": len(weld.index), "faces": len(F),
                 "keyframes": args.count, "bbox_diagonal": d,
                 "endpoint_error_reference": err0, "endpoint_error_target": err1,
                 "unwrapped_faces": int(np.count_nonzero(interp.turns)),
                 "global_rotation_deg": float(np.degrees(np.linalg.norm(interp.global_omega)))},
        docs=DOCS)


if __name__ == "__main__":
    run_stage(build_parser(), main)
