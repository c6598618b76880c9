"""Where the integrated field's error comes from (`make bench`, or alone: `.venv/bin/python benchmarks/accuracy.py`).

Writes reports/bench/accuracy.md and accuracy.json from the pipeline's results of lion, cat and horse (run the
pipeline first; `make bench` does). Per pose: fit + integrate seconds (Snakemake's benchmark files), the fit's
max error at the constraints, and the integrated V_C deviation from the target before any snap (integrate.h5, which
the benchmark runs keep). For
the V_C vertex that ends farthest from its target, two measurements along its *exact* constraint curve c(t)
(the cubic spline through its samples, 97 times):

* **field error**: |f(c(t), tau t) - c'(t)| / d, mean and max: the velocity error a perfect integrator would
  follow, between the samples as well as at them;
* **stretch**: exp of the integral of the largest eigenvalue of the symmetric part of the field's spatial
  Jacobian (central differences): how much the field amplifies an offset from the curve. A deviation of
  about stretch x mean field error is what the integration can reach.
"""

import argparse
import json
import os
from pathlib import Path

import h5py
import numpy as np
from scipy.interpolate import CubicSpline

from posefix.workflow.timings import benchmark_seconds
from posefix.spacetime.rbf import RBFField

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSEFIX_DATA", ROOT.parent / "shared" / "data"))
LIBRARIES = ("lion-poses", "cat-poses", "horse-poses")
BAR = 2e-3
"""Issue 19's bar: integrated V_C max deviation / d."""
CURVE_TIMES = 97


def pose_row(folder):
    """Measurements of one pose from its results folder (dict)."""
    with h5py.File(folder / "constraints.h5", "r") as fh:
        Y, vertex, time = fh["points"][()], fh["vertex"][()], fh["time"][()]
        d, tau = float(fh["metrics"].attrs["bbox_diagonal"]), float(fh["metrics"].attrs["tau"])
        samples = int(fh["metrics"].attrs["samples"])
    with h5py.File(folder / "fit.h5", "r") as fh:
        field = RBFField(fh["centers"][()], fh["weights"][()], fh["poly"][()], fh["shift"][()], float(fh["scale"][()]))
        fit_error = float(fh["metrics"].attrs["max_error_rel"])
    with h5py.File(folder / "integrate.h5", "r") as fi, h5py.File(folder / "keyframes.h5", "r") as fk:
        deviation = np.linalg.norm(fi["positions"][()] - fk["target"][()], axis=1) / d  # the integrated pose's
    vc = np.unique(vertex)
    worst = int(vc[np.argmax(deviation[vc])])
    curve = CubicSpline(time[vertex == worst], Y[vertex == worst, :3], axis=0)
    error, stretch = curve_measurements(field, curve, tau, d)
    seconds = {s: benchmark_seconds(folder.parent / "benchmarks" / folder.name, s) for s in ("fit", "integrate")}
    return {"pose": folder.name, "samples": samples, "fit_seconds": seconds["fit"],
            "integrate_seconds": seconds["integrate"], "fit_max_error": fit_error,
            "vc_mean": float(deviation[vc].mean()), "vc_max": float(deviation[vc].max()), "worst_vertex": worst,
            "field_error_mean": float(error.mean()), "field_error_max": float(error.max()), "stretch": stretch}


def curve_measurements(field, curve, tau, d):
    """Field error along ``curve`` (CURVE_TIMES,) / d, and the stretch factor (float)."""
    t = np.linspace(0.0, 1.0, CURVE_TIMES)
    Y = np.concatenate([curve(t), tau * t[:, None]], axis=1)
    error = np.linalg.norm(field(Y) - curve(t, 1), axis=1) / d
    h = 1e-4 * d
    J = np.stack([(field(Y + h * np.eye(4)[a]) - field(Y - h * np.eye(4)[a])) / (2 * h) for a in range(3)], axis=2)
    rate = np.linalg.eigvalsh(0.5 * (J + J.transpose(0, 2, 1)))[:, -1]
    return error, float(np.exp(np.trapezoid(rate, t)))


def markdown(rows):
    """The section of BENCHMARKS.md (list of str)."""
    lines = ["## Integrated field accuracy: where the V_C deviation comes from", "",
             f"Bar (issue 19): integrated V_C max deviation <= {BAR:g} d before any snap. For the V_C vertex that ends "
             "farthest from its target: the field error along its exact constraint curve (between the samples as "
             "well as at them) and the field's stretch along it (benchmarks/accuracy.py says how).", "",
             "| library | pose | fit + integrate s | fit max error / d | V_C mean / max / d | <= bar | worst vertex: "
             "field error mean / max / d | stretch |", "|---|---|---:|---:|---|---|---|---:|"]
    for library, poses in rows.items():
        for r in poses:
            secs = (r["fit_seconds"] or 0) + (r["integrate_seconds"] or 0)
            lines.append(f"| {library} | {r['pose']} | {secs:.1f} | {r['fit_max_error']:.1e} | "
                         f"{r['vc_mean']:.1e} / {r['vc_max']:.1e} | {'yes' if r['vc_max'] <= BAR else 'no'} | "
                         f"{r['field_error_mean']:.1e} / {r['field_error_max']:.1e} | {r['stretch']:.1f} |")
    every = [r for poses in rows.values() for r in poses]
    if every:
        secs = [(r["fit_seconds"] or 0) + (r["integrate_seconds"] or 0) for r in every]
        lines += ["", f"{sum(r['vc_max'] <= BAR for r in every)} of {len(every)} poses reach the bar; fit + integrate "
                  f"{np.mean(secs):.1f} s per pose on average (max {max(secs):.1f} s; Snakemake's seconds, two jobs "
                  "sharing 2 cores); S0 on a GTX 460 + 4 cores: 42-74 s (issue 19, from S0 Table 1).", ""]
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--results", default=str(ROOT / "results"))
    parser.add_argument("--out", default=str(ROOT / "reports" / "bench"))
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = {}
    for library in LIBRARIES:
        folder = Path(args.results) / library
        poses = sorted(p for p in folder.glob("*") if (p / "verify.h5").exists() and (p / "fit.h5").exists())
        rows[library] = [pose_row(p) for p in poses]
        print(f"{library}: {len(poses)} poses", flush=True)
    (out / "accuracy.md").write_text("\n".join(markdown(rows)))
    (out / "accuracy.json").write_text(json.dumps(rows, indent=1))
    print(f"wrote {out / 'accuracy.md'}")


if __name__ == "__main__":
    main()
