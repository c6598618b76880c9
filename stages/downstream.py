"""Stage downstream: does a downstream nonlinear solver converge better on the repaired pose? (S0 §5)

Runs the example-driven discrete-shell deformation (Fröhlich & Botsch 2011; Gauss–Newton, see
``posefix.shells``) from the reference towards the original target and towards the repaired pose,
for every stiffness k_b in ``--k-bend`` and weight alpha in ``--alphas`` (a grid: single settings
are fragile). The same three far-apart handle vertices are pinned at their linear blend in every
run. Writes per-run iterations, convergence, stop reason and the error after every iteration, and
(``--png``) a figure of the energy per iteration (``posefix.figures.downstream_history``).
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "lib"))

import itertools  # noqa: E402

import posefix  # noqa: E402,F401  (runtime defaults before numpy)
import numpy as np  # noqa: E402

from posefix import figures  # noqa: E402
from posefix.cli import Timings, float_list, run_stage, stage_parser  # noqa: E402
from posefix.h5io import read_artifact, write_artifact  # noqa: E402
from posefix.io import write_figure  # noqa: E402
from posefix.shells import (EXAMPLES, STOP_REASONS, SolverSettings, deform_towards, handle_vertices,  # noqa: E402
                            mesh_hinges)

DOCS = {
    "alpha": ("1", "interpolation weight of the run's targets, (R,) float64"),
    "k_bend": ("1", "bending stiffness k_b of the run, (R,) float64"),
    "example": ("index", "example of the run: 0 original target, 1 repaired pose, (R,) uint8"),
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
    parser.add_argument("--alphas", type=float_list, default=[0.5, 1.0], help="interpolation weights, e.g. 0.5,1.0")
    parser.add_argument("--k-bend", type=float_list, default=[1e-3, 1e-2, 1e-1], help="bending stiffnesses k_b")
    parser.add_argument("--k-stretch", type=float, default=1.0, help="stretching stiffness k_l")
    defaults = SolverSettings()
    parser.add_argument("--max-iters", type=int, default=defaults.max_iters, help="Gauss-Newton iterations at most")
    parser.add_argument("--rel-tol", type=float, default=defaults.rel_tol,
                        help="stop when the relative decrease of the energy falls below this")
    parser.add_argument("--stall-iters", type=int, default=defaults.stall_iters,
                        help=f"stop as stalled after this many accepted steps below {defaults.stall_step} in a row")
    return parser


def main(args, log):
    timings = Timings()
    with timings.step("read", log):
        kf, _ = read_artifact(args.keyframes, "keyframes", ["reference", "target", "faces"])
        ve, _ = read_artifact(args.verify, "verify", ["repaired"])
    V_ref, F = kf["reference"], kf["faces"]
    examples = {"original": kf["target"], "repaired": ve["repaired"]}
    settings = SolverSettings(max_iters=args.max_iters, rel_tol=args.rel_tol, stall_iters=args.stall_iters)
    hinges, handles = mesh_hinges(F), handle_vertices(V_ref)
    grid = list(itertools.product(args.alphas, args.k_bend, range(len(EXAMPLES))))
    runs = []
    with timings.step("solve", log):
        for i, (alpha, k_bend, example) in enumerate(grid, 1):
            res = deform_towards(V_ref, F, examples[EXAMPLES[example]], alpha, args.k_stretch, k_bend, handles,
                                 settings, hinges, log)
            log.info("[%d/%d] alpha %g k_b %g %-8s: %3d iterations, %s, E %.3g (%.1f s)", i, len(grid), alpha, k_bend,
                     EXAMPLES[example], res.iterations, res.reason, res.errors[-1], res.seconds)
            runs.append(res)
    datasets = {
        "alpha": np.array([g[0] for g in grid]), "k_bend": np.array([g[1] for g in grid]),
        "example": np.array([g[2] for g in grid], dtype=np.uint8),
        "iterations": np.array([r.iterations for r in runs], dtype=np.int64),
        "converged": np.array([r.converged for r in runs]),
        "reason": np.array([STOP_REASONS.index(r.reason) for r in runs], dtype=np.uint8),
        "final_error": np.array([r.errors[-1] for r in runs]),
        "gradient_reduction": np.array([r.gradient_reduction for r in runs]),
        "min_area_ratio": np.array([r.min_area_ratio for r in runs]),
        "seconds": np.array([r.seconds for r in runs]),
        "errors": np.concatenate([r.errors for r in runs]),
        "error_offsets": np.cumsum([0] + [len(r.errors) for r in runs]).astype(np.int64),
        "handles": handles}
    metrics = {}
    for example, name in enumerate(EXAMPLES):
        sel = datasets["example"] == example
        metrics[f"{name}_converged"] = int(datasets["converged"][sel].sum())
        metrics[f"{name}_iterations"] = int(datasets["iterations"][sel].sum())
        log.info("%s: converged in %d of %d runs, %d iterations in all", name, metrics[f"{name}_converged"],
                 sel.sum(), metrics[f"{name}_iterations"])
    metrics["runs"] = len(grid)
    write_artifact(args.out, "downstream", datasets,
                   params={"alphas": args.alphas, "k_bend": args.k_bend, "k_stretch": args.k_stretch,
                           "max_iters": args.max_iters, "rel_tol": args.rel_tol, "stall_iters": args.stall_iters},
                   inputs=[args.keyframes, args.verify], timings=timings, metrics=metrics, docs=DOCS)
    if args.png:
        curves = [{"alpha": a, "k_bend": k, "example": EXAMPLES[e], "errors": r.errors, "converged": r.converged,
                   "reason": r.reason} for (a, k, e), r in zip(grid, runs)]
        write_figure(args.png, figures.downstream_history(curves, title=f"{args.pose}: Gauss-Newton discrete shells"))


if __name__ == "__main__":
    run_stage(build_parser(), main)
