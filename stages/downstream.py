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
from posefix.downstream.gauss_newton import SolverSettings
from posefix.io.artifacts import read_artifact, repaired_poses, write_artifact
from posefix.workflow.cli import add_repair_option, dataset_docs, run_stage, stage_parser
from posefix.workflow.stage_settings import DownstreamSettings
from posefix.io.files import write_figure
from posefix.workflow.timings import Timings
from posefix.report import figures


def build_parser():
    parser = stage_parser("downstream", __doc__, [(DownstreamSettings, "Gauss-Newton check (config downstream)")],
                          keyframes="keyframes.h5 of the pose (reference, target, faces)",
                          verify="verify.h5 of the pose (repaired positions)", out="downstream.h5 to write")
    add_repair_option(parser, "also deform towards its repaired pose")
    parser.add_argument("--png", default=None, help="also draw the energy per iteration of every run into this PNG")
    parser.add_argument("--pose", default="", help="pose name (figure title)")
    return parser


def main(args, log):
    timings = Timings()
    with timings.step("read"):
        kf, _ = read_artifact(args.keyframes, "keyframes", ["reference", "target", "faces"])
        ve, _ = read_artifact(args.verify, "verify", ["repaired"])
        examples = {"original": kf["target"], "repaired": ve["repaired"]} | repaired_poses(args.repair)
    settings = SolverSettings(max_iters=args.max_iters, rel_tol=args.rel_tol, stall_iters=args.stall_iters)
    with timings.step("solve"):
        check = downstream_check(kf["reference"], kf["faces"], examples, args.alphas, args.k_bend, args.k_stretch,
                                 settings, workers=args.threads)
    write_artifact(args.out, "downstream", check.datasets(),
                   params={"alphas": args.alphas, "k_bend": args.k_bend, "k_stretch": args.k_stretch,
                           "max_iters": args.max_iters, "rel_tol": args.rel_tol, "stall_iters": args.stall_iters,
                           "repairs": [name for name, _ in args.repair]},
                   inputs=[args.keyframes, args.verify, *(path for _, path in args.repair)], timings=timings,
                   metrics=check.metrics(), docs=dataset_docs("downstream"))
    if args.png:
        title = f"{args.pose}: Gauss-Newton discrete shells"
        write_figure(args.png, figures.downstream_history(check.curves(), title=title))


if __name__ == "__main__":
    run_stage(build_parser(), main)
