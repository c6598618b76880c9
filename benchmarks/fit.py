"""Fit benchmark: the counterpart of S0 Table 1 on our machines.

For every pose of a library (``results/<library>/<pose>/``, from the pipeline):

* centres, iterations, max kappa and fit seconds of (fps, blocked) - the defaults - on all poses,
  read from the pipeline's ``fit.h5`` (its seconds were measured inside the pipeline run);
* (fps, full) and (worst, blocked) refitted on the first ``--variant-poses`` poses;
* seconds per iteration (update + solve) of blocked vs full at the same numbers of centres;
* a peer check: ``scipy.interpolate.RBFInterpolator(kernel="thin_plate_spline", degree=2)`` fitted on
  the final centres of the (fps, full) fits (the same centres as the defaults') must give the same
  field (max difference relative to the field's magnitude) - and its fit time.

    python benchmarks/fit.py --library lion-poses --out reports/bench/fit-lion-poses
"""

import argparse
import json
import time
from pathlib import Path

import posefix  # noqa: F401  (runtime defaults before numpy)
import h5py
import numpy as np
from scipy.interpolate import RBFInterpolator
from threadpoolctl import threadpool_limits

from posefix.spacetime.fit import FitSettings, iterate, start_fit

VARIANTS = (("fps", "blocked"), ("fps", "full"), ("worst", "blocked"))
SIZES = (1000, 2000, 3000)


def fit_pose(path, selection, update, config):
    with h5py.File(path, "r") as fh:
        Y, V = fh["points"][()], fh["values"][()]
        d = float(fh["metrics"].attrs["bbox_diagonal"])
    settings = FitSettings(eps=config["eps_rel"] * d, max_centers=config["max_centers"], batch=config["batch"],
                           candidates=config["candidates"], selection=selection, update=update)
    start = time.perf_counter()
    fit = start_fit(Y, V, settings)
    reason = iterate(fit)
    seconds = time.perf_counter() - start
    return fit, reason, seconds, d


def peer_check(fit, probes=2000):
    """Max |ours - scipy| / max |ours| on constraint points, and scipy's fit seconds."""
    centres = fit.points[fit.order]
    start = time.perf_counter()
    peer = RBFInterpolator(centres, fit.values[fit.order], kernel="thin_plate_spline", degree=2)
    seconds = time.perf_counter() - start
    idx = np.random.default_rng(0).choice(len(fit.points), min(probes, len(fit.points)), replace=False)
    ours = fit.field()(fit.points[idx])
    return float(np.abs(ours - peer(fit.points[idx])).max() / np.abs(ours).max()), seconds


def pipeline_fit(path, pose):
    """The (fps, blocked) row of a pose from the pipeline's fit.h5, and its (centres, seconds) per iteration."""
    with h5py.File(path, "r") as fh:
        m = dict(fh["metrics"].attrs)
        history = [(int(c), float(u + s)) for c, u, s in zip(fh["history/centers"][()], fh["history/seconds_update"][()],
                                                            fh["history/seconds_solve"][()])]
        constraints = len(fh["residual"])
    row = {"pose": pose, "selection": "fps", "update": "blocked", "constraints": constraints,
           "centers": int(m["centers"]), "iterations": int(m["iterations"]), "stop": str(m["stop_reason"]),
           "max_condition": float(m["max_condition"]), "max_error_rel": float(m["max_error_rel"]),
           "rms_error_rel": float(m["rms_error_rel"]), "seconds": float(m["seconds"])}
    return row, history


def iteration_seconds(fit):
    """(centres, update + solve seconds) of every iteration."""
    return [(r["centers"], r["seconds_update"] + r["seconds_solve"]) for r in fit.history]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--library", required=True)
    parser.add_argument("--results", default=None, help="default: results/<library>")
    parser.add_argument("--out", required=True, help="output path without extension (.json, .md)")
    parser.add_argument("--variant-poses", type=int, default=3, help="poses on which all variants run")
    parser.add_argument("--config", default="config.yaml", help="fit defaults (the 'fit' section)")
    args = parser.parse_args()
    import yaml
    config = yaml.safe_load(Path(args.config).read_text())["fit"]
    results = Path(args.results or f"results/{args.library}")
    poses = sorted(p.parent.name for p in results.glob("*/constraints.h5"))
    rows, timing = [], {}
    with threadpool_limits(1):
        for i, pose in enumerate(poses):
            row, history = pipeline_fit(results / pose / "fit.h5", pose)
            rows.append(row)
            timing.setdefault("blocked", []).extend(history)
            for selection, update in VARIANTS[1:] if i < args.variant_poses else ():
                fit, reason, seconds, d = fit_pose(results / pose / "constraints.h5", selection, update, config)
                row = {"pose": pose, "selection": selection, "update": update, "constraints": len(fit.points),
                       "centers": fit.n, "iterations": len(fit.history), "stop": reason,
                       "max_condition": max(r["condition"] for r in fit.history),
                       "max_error_rel": fit.history[-1]["max_error"] / d,
                       "rms_error_rel": fit.history[-1]["rms_error"] / d, "seconds": seconds}
                if selection == "fps":
                    row["peer_difference"], row["peer_seconds"] = peer_check(fit)
                    timing.setdefault(update, []).extend(iteration_seconds(fit))
                rows.append(row)
                print(json.dumps(row), flush=True)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps({"library": args.library, "config": config, "rows": rows,
                                                    "iteration_seconds": timing}, indent=1))
    out.with_suffix(".md").write_text(markdown(args.library, config, rows, timing))
    print(markdown(args.library, config, rows, timing))


def _nearest(pairs, n):
    """Seconds of the iteration whose centre count is closest to ``n`` (None if far off)."""
    if not pairs:
        return None
    c, s = min(pairs, key=lambda p: abs(p[0] - n))
    return s if abs(c - n) <= 128 else None


def markdown(library, config, rows, timing):
    lines = [f"### Fit: {library}", "",
             f"Defaults: eps_rel {config['eps_rel']}, max_centers {config['max_centers']}, p = {config['candidates']}, "
             f"m = {config['batch']}; one BLAS thread. fps / blocked: the pipeline's own fits (its seconds, "
             "two fits running side by side on the 2 cores); the variants are refitted alone.", "",
             "| selection / update | poses | centres (mean) | iterations | max kappa | max error / d | rms error / d | fit s (mean) |",
             "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for selection, update in VARIANTS:
        sub = [r for r in rows if (r["selection"], r["update"]) == (selection, update)]
        if not sub:
            continue
        lines.append(f"| {selection} / {update} | {len(sub)} | {np.mean([r['centers'] for r in sub]):.0f} | "
                     f"{np.mean([r['iterations'] for r in sub]):.1f} | {max(r['max_condition'] for r in sub):.2g} | "
                     f"{np.mean([r['max_error_rel'] for r in sub]):.2g} | {np.mean([r['rms_error_rel'] for r in sub]):.2g} | "
                     f"{np.mean([r['seconds'] for r in sub]):.1f} |")
    lines += ["", "| centres | blocked s / iteration | full s / iteration | full / blocked |", "|---:|---:|---:|---:|"]
    for n in SIZES:
        b, f = _nearest(timing.get("blocked", []), n), _nearest(timing.get("full", []), n)
        if b is not None and f is not None:
            lines.append(f"| {n} | {b:.3f} | {f:.3f} | {f / b:.1f} |")
    peers = [r for r in rows if "peer_difference" in r]
    if peers:
        lines += ["", "Peer check (scipy RBFInterpolator, thin_plate_spline, degree 2, on the final centres): "
                  f"max relative difference {max(r['peer_difference'] for r in peers):.1e}; scipy fit "
                  f"{np.mean([r['peer_seconds'] for r in peers]):.1f} s vs ours (fps / full) "
                  f"{np.mean([r['seconds'] for r in peers]):.1f} s (ours includes the greedy selection)."]
    lines += ["", "| pose | selection / update | centres | iterations | stop | max kappa | max error / d | rms error / d | s |",
              "|---|---|---:|---:|---|---:|---:|---:|---:|"]
    lines += [f"| {r['pose']} | {r['selection']} / {r['update']} | {r['centers']} | {r['iterations']} | {r['stop']} | "
              f"{r['max_condition']:.2g} | {r['max_error_rel']:.2g} | {r['rms_error_rel']:.2g} | {r['seconds']:.1f} |"
              for r in rows]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
