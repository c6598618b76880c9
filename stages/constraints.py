"""Stage constraints: space-time interpolation constraints of the vector field (S0 §4.1).

Every vertex of V_C follows a C1 cubic trajectory through its key-frame positions (tangents by
finite differences as in S0 §4.1, or of a per-vertex cubic spline); sampling it at t_i = i/s gives the
space-time points y = (c(t_i), tau t_i) and tangents c'(t_i) the field must interpolate. See
``posefix.spacetime.constraints``.
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

from posefix.mesh.geometry import bbox_diagonal
from posefix.io.artifacts import read_artifact, write_artifact
from posefix.io.keyframes import read_keyframes
from posefix.workflow.cli import dataset_docs, run_stage, stage_parser
from posefix.io.errors import InputError
from posefix.workflow.timings import Timings
from posefix.spacetime.constraints import spacetime_constraints
from posefix.workflow.stage_settings import ConstraintsSettings


def build_parser():
    return stage_parser("constraints", __doc__, [(ConstraintsSettings, "constraints (config constraints)")],
                        keyframes="keyframes.h5 of the pose", classify="classify.h5 of the pose (V_C)",
                        out="constraints.h5 to write")


def main(args, log):
    if args.samples < 2 or args.tau <= 0:
        raise InputError("arguments", "--samples must be >= 2 and --tau > 0")
    timings = Timings()
    with timings.step("read"):
        kf, _ = read_keyframes(args.keyframes, ["frames", "t", "reference"])
        cl, _ = read_artifact(args.classify, "classify", ["mask"])
    if cl["mask"].shape[0] != kf["reference"].shape[0]:
        raise InputError(args.classify, "V_C mask does not match the key frames' vertex count")
    d = bbox_diagonal(kf["reference"])
    with timings.step("sample"):
        points, values, vertex, time = spacetime_constraints(kf["frames"], kf["t"], cl["mask"], args.samples,
                                                             tau=args.tau * d, tangents=args.tangents)
    log.info("%d constraints: %d vertices x %d times, tau = %.3g (%.3g d), %s tangents", len(points),
             cl["mask"].sum(), args.samples + 1, args.tau * d, args.tau, args.tangents)
    write_artifact(
        args.out, "constraints", {"points": points, "values": values, "vertex": vertex, "time": time},
        params={"samples": args.samples, "tau": args.tau, "tangents": args.tangents},
        inputs=[args.keyframes, args.classify], timings=timings,
        metrics={"constraints": len(points), "constraint_vertices": int(cl["mask"].sum()),
                 "samples": args.samples, "tau": args.tau * d, "bbox_diagonal": d},
        docs=dataset_docs("constraints"))


if __name__ == "__main__":
    run_stage(build_parser(), main)
