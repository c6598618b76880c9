"""Stage integrate: move every reference vertex through the fitted space-time field (S0 §4.3).

dx/dt = f(x, tau t) from t = 0 to 1 with an embedded Dormand-Prince RK 5(4) and per-vertex adaptive
steps, on an OpenCL device (one work-item per vertex, float64) or, when none is available or
``--device numpy`` is given, with the vectorized numpy implementation of the same integrator.
Steps land on the constraint sample times t_i = i/s, where positions are recorded.
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)
import numpy as np

from posefix.io.artifacts import read_artifact, write_artifact
from posefix.workflow.cli import dataset_docs, run_stage, stage_parser
from posefix.io.errors import InputError
from posefix.workflow.resources import opencl_device
from posefix.workflow.timings import Timings
from posefix.workflow.stage_settings import IntegrateSettings
from posefix.spacetime.integration_opencl import path_lines
from posefix.spacetime.rbf import RBFField


def build_parser():
    return stage_parser("integrate", __doc__, [(IntegrateSettings, "integration (config integrate)")],
                        fit="fit.h5 of the pose (the field, tau, sample count)",
                        keyframes="keyframes.h5 of the pose (reference positions)", out="integrate.h5 to write")


def main(args, log):
    if args.rtol <= 0 or args.atol_rel <= 0 or not 0 < args.h0 <= 1:
        raise InputError("arguments", "--rtol and --atol-rel must be > 0 and --h0 in (0, 1]")
    timings = Timings()
    with timings.step("read"):
        fit, fattrs = read_artifact(args.fit, "fit", ["centers", "weights", "poly", "shift", "scale"])
        kf, _ = read_artifact(args.keyframes, "keyframes", ["reference"])
    field = RBFField(fit["centers"], fit["weights"], fit["poly"], fit["shift"], float(fit["scale"]))
    metrics = fattrs["metrics"]
    tau, d, s = float(metrics["tau"]), float(metrics["bbox_diagonal"]), int(metrics["samples"])
    times = np.arange(s + 1) / s
    X0 = kf["reference"]
    device, device_name = opencl_device(args.device, args.threads)
    backend = "numpy" if device is None else "opencl"
    log.info("integrating %d vertices through %d centres on %s (rtol %.1e, atol %.1e d)", len(X0), len(field.weights),
             device_name, args.rtol, args.atol_rel)
    with timings.step("integrate"):
        X1, samples, steps, rejected = path_lines(field, tau, X0, times, device,
                                                  (args.rtol, args.atol_rel * d, args.h0), args.vec or None)
    log.info("steps per vertex: mean %.1f, max %d; rejected: %d in all", steps.mean(), steps.max(), rejected.sum())
    lost = ~(np.isfinite(samples).all(axis=(0, 2)) & np.isfinite(X1).all(axis=1))
    if lost.any():  # (either backend)
        raise InputError(args.fit, f"the path lines of {lost.sum()} vertices are not finite (first: vertex "
                                   f"{np.argmax(lost)}): the fitted field is degenerate")
    write_artifact(
        args.out, "integrate",
        {"positions": X1, "samples": samples, "sample_times": times, "steps": steps, "rejected": rejected},
        params={"device": args.device, "rtol": args.rtol, "atol_rel": args.atol_rel, "h0": args.h0, "vec": args.vec},
        inputs=[args.fit, args.keyframes], timings=timings,
        metrics={"backend": backend, "device": device_name, "seconds": timings["integrate"],
                 "steps_mean": float(steps.mean()), "steps_max": int(steps.max()),
                 "rejected": int(rejected.sum()), "centers": len(field.weights), "bbox_diagonal": d},
        docs=dataset_docs("integrate"))


if __name__ == "__main__":
    run_stage(build_parser(), main)
