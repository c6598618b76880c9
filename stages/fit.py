"""Stage fit: greedy RBF fit of the space-time vector field f: R^4 -> R^3 (S0 §4.2).

Farthest-point greedy centre selection within the worst candidates, blocked Cholesky updates of
the null-space-projected system (or full LU refactorization), a condition estimate every
iteration, and a crash-safe checkpoint after every iteration: rerunning after a kill continues
from the stored factors and gives the same result as an uninterrupted fit. The checkpoint is
removed once fit.h5 is written, unless ``--keep-checkpoint`` (then a rerun with another stopping
rule on the same constraints continues from it too). See ``posefix.spacetime.fit`` and
``posefix.spacetime.factorization``.
"""

import json
from contextlib import contextmanager
from pathlib import Path

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)
import numpy as np

from posefix.spacetime import fit_checkpoint as checkpoint
from posefix.io.artifacts import config_hash, read_artifact, source_file, write_artifact
from posefix.workflow.cli import dataset_docs, run_stage, stage_parser
from posefix.workflow.stage_settings import FitOptions
from posefix.io.errors import InputError
from posefix.io.files import file_sha256
from posefix.workflow.resources import cache_budget, opencl_device
from posefix.workflow.timings import Timings
from posefix.spacetime.factorization import FactorizationError
from posefix.spacetime.fit import FitSettings, cache_fits, fit_memory, iterate


def build_parser():
    parser = stage_parser("fit", __doc__, [(FitOptions, "fit (config fit)")],
                          constraints="constraints.h5 of the pose", out="fit.h5 to write")
    parser.add_argument("--checkpoint", default=None, help="checkpoint folder (default: <out> with .checkpoint)")
    parser.add_argument("--mem-mb", type=float, default=None, help="the job's memory (MB; the rule's resources)")
    return parser


@contextmanager
def _refused_as_input(path):
    """Within: a :class:`FactorizationError` (constraints that make no well-posed fit) is an InputError on the file
    the constraints ``path`` were made from (the target pose's, a temporary constraints.h5 being gone by the time
    its user reads the message)."""
    try:
        yield
    except FactorizationError as exc:
        raise InputError(source_file(path), str(exc)) from None


def main(args, log):
    if args.max_centers < 16 or args.batch < 1 or args.candidates < args.batch or args.eps_rel < 0:
        raise InputError("arguments", "need --max-centers >= 16, --batch >= 1, --candidates >= --batch, --eps-rel >= 0")
    timings = Timings()
    with timings.step("read"):
        data, attrs = read_artifact(args.constraints, "constraints", ["points", "values"])
    d = float(attrs["metrics"]["bbox_diagonal"])
    points, values = data["points"], data["values"]
    budget = cache_budget(args.memory_gb * 1e9, args.mem_mb, fit_memory(len(points), args.max_centers))
    settings = FitSettings(eps=args.eps_rel * d, eps_rms=args.eps_rms_rel * d, max_centers=args.max_centers,
                           candidates=args.candidates, batch=args.batch, selection=args.selection,
                           update=args.update, memory_bytes=budget)
    device, device_name = (None, "none needed") if cache_fits(len(points), settings) else \
        opencl_device(args.device, args.threads)
    folder = Path(args.checkpoint or Path(args.out).with_suffix(".checkpoint"))
    key = config_hash({"constraints": file_sha256(args.constraints), **settings.selection_key()})
    log.info("%d constraints; eps = %.3g (%.3g d), max %d centres, %s selection, %s update",
             len(points), settings.eps, args.eps_rel, args.max_centers, args.selection, args.update)
    with checkpoint.locked(folder), _refused_as_input(args.constraints):
        with timings.step("start"):
            fit, resumed = checkpoint.start_or_resume(points, values, settings, folder, key, device)
        with timings.step("iterate"):
            reason = iterate(fit, on_iteration=checkpoint.committer(folder, key, _settings_dict(settings), fit,
                                                                    resumed))
    last = fit.history[-1]
    log.info("stopped (%s) at %d centres: max error %.3g d, rms %.3g d, max kappa %.3g", reason, fit.n,
             last["max_error"] / d, last["rms_error"] / d, max(r["condition"] for r in fit.history))
    history = {name: np.array([r[name[len("history/"):]] for r in fit.history]) for name in dataset_docs("fit")
               if name.startswith("history/")}
    write_artifact(
        args.out, "fit",
        {"centers": points[fit.order], "center_index": fit.order, "weights": fit.weights, "poly": fit.poly,
         "shift": fit.shift, "scale": np.float64(fit.scale), **history},
        params=_settings_dict(settings) | {"eps_rel": args.eps_rel, "eps_rms_rel": args.eps_rms_rel,
                                           "device": args.device},
        inputs=[args.constraints], timings=timings,
        metrics={"centers": fit.n, "iterations": len(fit.history), "stop_reason": reason,
                 "evaluation": fit.evaluator.mode, "device": device_name,
                 "max_error_rel": last["max_error"] / d, "rms_error_rel": last["rms_error"] / d,
                 "max_condition": max(r["condition"] for r in fit.history), "bbox_diagonal": d,
                 "tau": float(attrs["metrics"]["tau"]), "samples": int(attrs["metrics"]["samples"]),
                 "constraints": len(points), "constraint_vertices": int(attrs["metrics"]["constraint_vertices"]),
                 "resumed_iterations": resumed,
                 "seconds": sum(timings.get(k, 0.0) for k in ("start", "iterate"))},
        docs=dataset_docs("fit"))
    if not args.keep_checkpoint:
        checkpoint.remove(folder)


def _settings_dict(settings):
    return json.loads(json.dumps(settings.__dict__))


if __name__ == "__main__":
    run_stage(build_parser(), main)
