"""Stage downstream: does a downstream nonlinear solver converge better on the repaired pose? (S0 §5)

Runs the example-driven discrete-shell deformation (Fröhlich & Botsch 2011; Gauss–Newton, see
``posefix.downstream``) from the reference towards the original target and towards the repaired pose,
for every stiffness k_b in ``--k-bend`` and weight alpha in ``--alphas`` (one setting by default;
``make bench`` runs the grid ``posefix.downstream.check.GRID``, as single settings are fragile). The same three far-apart handle vertices are pinned at their linear blend in every
run; every ``--repair`` is a further example, checked over the same grid. Writes per-run
iterations, convergence, stop reason and the error after every iteration, and (``--png``) a figure
of the energy per iteration (``posefix.report.figures.downstream_history``). With ``--threads`` N, N
runs at a time (processes of one thread each; the same iterations and stop reasons).
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

from posefix.downstream.check import downstream_check
from posefix.downstream.gauss_newton import STOP_REASONS, SolverSettings
from posefix.io.artifacts import read_artifact, read_repair, write_artifact
from posefix.workflow.cli import named_path, run_stage, stage_parser
from posefix.workflow.settings import add_settings_options
from posefix.workflow.stage_settings import DownstreamSettings
from posefix.io.files import write_figure
from posefix.workflow.timings import Timings
from posefix.report import figures

DOCS = {
    "alpha": ("1", "interpolation weight of the run's targets, (R,) float64"),
    "k_bend": ("1", "bending stiffness k_b of the run, (R,) float64"),
    "example": ("index", "example of the run: 0 original target, 1 repaired pose, 2... the other repairs (examples), "
                         "(R,) uint8"),
    "examples": ("name", "name of each example code: original, repaired, then the other repairs, (E,) str"),
    "iterations": ("count", "accepted Gauss-Newton steps, (R,) int64"),
    "converged": ("bool", "energy zero, or a full step accepted with |J^T r| reduced 1e4-fold, (R,) bool"),
    "reason": ("index", "stop reason: " + ", ".join(f"{i} {r}" for i, r in enumerate(STOP_REASONS)) + ", (R,) uint8"),
    "final_error": ("1", "energy sum r^2 at the end, (R,) float64"),
    "gradient_reduction": ("1", "|J^T r| at the start / at the end, (R,) float64"),
    "min_area_ratio": ("1", "smallest face area / its reference area at the end, (R,) float64"),
    "seconds": ("s", "wall time of the run, (R,) float64"),
    "errors": ("1", "energy at the start and after every accepted step, all runs concatenated, (sum(iterations + 1),) float64"),
    "error_offsets": ("index", "run i's errors are errors[error_offsets[i]:error_offsets[i + 1]], (R + 1,) int64"),
    "handles": ("index", "pinned vertices (far apart, farthest-point sampling), (3,) int64"),
}


def build_parser():
    parser = stage_parser("downstream", __doc__)
    parser.add_argument("--keyframes", required=True, help="keyframes.h5 of the pose (reference, target, faces)")
    parser.add_argument("--verify", required=True, help="verify.h5 of the pose (repaired positions)")
    parser.add_argument("--out", required=True, help="downstream.h5 to write")
    parser.add_argument("--png", default=None, help="also draw the energy per iteration of every run into this PNG")
    parser.add_argument("--pose", default="", help="pose name (figure title)")
    parser.add_argument("--repair", type=named_path, action="append", default=[], metavar="NAME=PATH",
                        help="another repair's artifact (e.g. medial=<pose>/medial.h5): also deform towards its "
                        "repaired pose; repeatable")
    add_settings_options(parser, DownstreamSettings, "Gauss-Newton check (config downstream)")
    return parser


def main(args, log):
    timings = Timings()
    with timings.step("read"):
        kf, _ = read_artifact(args.keyframes, "keyframes", ["reference", "target", "faces"])
        ve, _ = read_artifact(args.verify, "verify", ["repaired"])
        examples = {"original": kf["target"], "repaired": ve["repaired"]}
        examples |= {name: read_repair(path, name, ["repaired"])[0]["repaired"] for name, path in args.repair}
    settings = SolverSettings(max_iters=args.max_iters, rel_tol=args.rel_tol, stall_iters=args.stall_iters)
    with timings.step("solve"):
        check = downstream_check(kf["reference"], kf["faces"], examples, args.alphas, args.k_bend, args.k_stretch,
                                 settings, workers=args.threads)
    write_artifact(args.out, "downstream", check.datasets(),
                   params={"alphas": args.alphas, "k_bend": args.k_bend, "k_stretch": args.k_stretch,
                           "max_iters": args.max_iters, "rel_tol": args.rel_tol, "stall_iters": args.stall_iters,
                           "repairs": [name for name, _ in args.repair]},
                   inputs=[args.keyframes, args.verify, *(path for _, path in args.repair)], timings=timings,
                   metrics=check.metrics(), docs=DOCS)
    if args.png:
        title = f"{args.pose}: Gauss-Newton discrete shells"
        write_figure(args.png, figures.downstream_history(check.curves(), title=title))


if __name__ == "__main__":
    run_stage(build_parser(), main)
