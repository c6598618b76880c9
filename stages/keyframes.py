"""Stage keyframes: key frames from the reference to one target pose (S0 §4.1).

Gradient-space interpolation (Xu et al. 2005) with global rigid alignment and rotation-branch
unwrapping; see ``posefix.spacetime.keyframes`` for the method. Writes ``keyframes.h5`` with the two input poses, the
K - 2 inner frames at t = k/(K-1) as float32 offsets from their linear blend (``posefix.io.keyframes``), and
per-face rotation diagnostics.
"""

from pathlib import Path

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)
import numpy as np

from posefix.mesh.geometry import bbox_diagonal
from posefix.io.artifacts import write_artifact
from posefix.io.keyframes import frame_offsets
from posefix.workflow.cli import dataset_docs, run_stage, stage_parser
from posefix.io.library import read_welded_pair
from posefix.workflow.timings import Timings
from posefix.spacetime import keyframes as kf
from posefix.workflow.stage_settings import KeyframesSettings


def build_parser():
    return stage_parser("keyframes", __doc__, [(KeyframesSettings, "key frames (config keyframes)")],
                        reference="reference mesh file", target="target pose mesh file", out="keyframes.h5 to write")


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
        {"t": t, "frame_offsets": frame_offsets(frames, t, V_ref, V_tgt), "faces": F, "reference": V_ref,
         "target": V_tgt, "weld_index": weld.index, "rotation_angle": angle.astype(np.float32),
         "branch_turns": interp.turns, "global_rotation": interp.global_omega},
        params={"count": args.count, "align": args.align, "unwrap": args.unwrap},
        inputs=[args.reference, args.target], timings=timings,
        metrics={"vertices": len(V_ref), "input_vertices": len(weld.index), "faces": len(F),
                 "keyframes": args.count, "bbox_diagonal": d,
                 "endpoint_error_reference": err0, "endpoint_error_target": err1,
                 "unwrapped_faces": int(np.count_nonzero(interp.turns)),
                 "global_rotation_deg": float(np.degrees(np.linalg.norm(interp.global_omega)))},
        docs=dataset_docs("keyframes"))


if __name__ == "__main__":
    run_stage(build_parser(), main)
