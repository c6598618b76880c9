"""Measure what the fit's defaults do to the repaired poses: new intersections and deviation.

For each pose and each configuration (tau, tangents, samples, contact, max_centres, eps_rel) this
runs classification (when contact differs), constraints, the greedy fit and a numpy RK45
integration (OpenCL when available) of every reference vertex, and reports centres, max kappa, fit error, fit and
integration seconds, new intersecting faces (intersecting in the result, not in the reference)
and deviation from the target over V_C and its complement (relative to the bbox diagonal).
Key frames come from ``results/<library>/<pose>/keyframes.h5`` (run the pipeline first).

    python benchmarks/fit_defaults.py --library lion-poses --poses lion-01,lion-04 \
        --grid "tau=0.05,0.1,0.3" --out reports/bench/fit-defaults-tau
"""

import argparse
import itertools
import json
import time
from pathlib import Path

import posefix  # noqa: F401  (runtime defaults before numpy)
import numpy as np

from posefix.io.keyframes import read_keyframes
from posefix.mesh.contacts import contact_vertices
from posefix.mesh.geometry import bbox_diagonal
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.spacetime.classification import constraint_mask
from posefix.spacetime.constraints import spacetime_constraints
from posefix.spacetime.fit import FitSettings, iterate, start_fit
from posefix.spacetime.integration import field_velocity, rk45
from posefix.spacetime.integration_opencl import rk45_opencl, select_device

BASE = {"tau": 0.1, "tangents": "spline", "samples": 12, "contact": 0.0, "max_centers": 4000, "eps_rel": 1e-4,
        "ring": 1, "batch": 128}


def parse_grid(text):
    """``"tau=0.05,0.1;contact=0,0.01"`` -> list of config dicts (the product, over BASE)."""
    axes = []
    for part in filter(None, text.split(";")):
        key, values = part.split("=")
        cast = type(BASE[key])
        axes.append([(key, cast(v) if cast is not float else float(v)) for v in values.split(",")])
    return [dict(BASE, **dict(combo)) for combo in itertools.product(*axes)] if axes else [dict(BASE)]


def run(results, pose, cfg, classify_cache):
    kf, _ = read_keyframes(Path(results) / pose / "keyframes.h5", ["frames", "t", "faces"])
    frames, t, F = kf["frames"], kf["t"], kf["faces"]
    V_ref, V_tgt = frames[0], frames[-1]
    d = bbox_diagonal(V_ref)
    key = (cfg["contact"], cfg["ring"])
    if key not in classify_cache:
        pairs = [self_intersecting_pairs(V, F) for V in frames]
        contacts = contact_vertices(frames, F, V_ref, cfg["contact"] * d, 0.1 * d) if cfg["contact"] > 0 else None
        classify_cache[key] = (constraint_mask(F, len(V_ref), pairs, ring=cfg["ring"], contacts=contacts)[0], pairs[0])
    mask, ref_pairs = classify_cache[key]
    Y, V, _, _ = spacetime_constraints(frames, t, mask, cfg["samples"], tau=cfg["tau"] * d, tangents=cfg["tangents"])
    start = time.perf_counter()
    fit = start_fit(Y, V, FitSettings(eps=cfg["eps_rel"] * d, max_centers=cfg["max_centers"], batch=cfg["batch"]))
    reason = iterate(fit)
    fit_s = time.perf_counter() - start
    start = time.perf_counter()
    device, _ = select_device("auto")
    if device is not None:
        X, _, steps, _ = rk45_opencl(device, fit.field(), cfg["tau"] * d, V_ref, [0.0, 1.0], 1e-9, 1e-7 * d)
    else:
        X, _, steps, _ = rk45(field_velocity(fit.field(), cfg["tau"] * d), V_ref, rtol=1e-9, atol=1e-7 * d)
    int_s = time.perf_counter() - start
    ref_faces = intersecting_faces(ref_pairs, len(F))
    rep_faces = intersecting_faces(self_intersecting_pairs(X, F), len(F))
    tgt_faces = intersecting_faces(self_intersecting_pairs(V_tgt, F), len(F))
    dev = np.linalg.norm(X - V_tgt, axis=1) / d
    last = fit.history[-1]
    return {"pose": pose, **cfg, "constraints": len(Y), "vc": int(mask.sum()), "centers": fit.n, "stop": reason,
            "max_error_rel": last["max_error"] / d, "rms_error_rel": last["rms_error"] / d,
            "max_condition": max(r["condition"] for r in fit.history), "fit_seconds": fit_s,
            "integrate_seconds": int_s, "steps_mean": float(steps.mean()),
            "target_faces": int(tgt_faces.sum()), "repaired_faces": int(rep_faces.sum()),
            "new_faces": int((rep_faces & ~ref_faces).sum()),
            "dev_c_mean": float(dev[mask].mean()), "dev_c_max": float(dev[mask].max()),
            "dev_c_p95": float(np.percentile(dev[mask], 95)),
            "dev_free_mean": float(dev[~mask].mean()) if (~mask).any() else 0.0,
            "dev_free_max": float(dev[~mask].max()) if (~mask).any() else 0.0}


COLUMNS = ("pose", "tau", "tangents", "samples", "contact", "max_centers", "batch", "vc", "centers", "stop",
           "max_error_rel", "rms_error_rel", "max_condition", "fit_seconds", "integrate_seconds", "target_faces",
           "new_faces", "dev_c_mean", "dev_c_p95", "dev_c_max", "dev_free_max")


def markdown(rows):
    def fmt(v):
        return f"{v:.3g}" if isinstance(v, float) else str(v)
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    lines += ["| " + " | ".join(fmt(r[c]) for c in COLUMNS) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--library", default="lion-poses")
    parser.add_argument("--results", default=None, help="default: results/<library>")
    parser.add_argument("--poses", required=True)
    parser.add_argument("--grid", default="", help='e.g. "tau=0.05,0.1,0.3;tangents=hermite,spline"')
    parser.add_argument("--out", required=True, help="output path without extension (.json, .md)")
    args = parser.parse_args()
    results = args.results or f"results/{args.library}"
    rows = []
    for pose in args.poses.split(","):
        cache = {}
        for cfg in parse_grid(args.grid):
            rows.append(run(results, pose, cfg, cache))
            print(markdown(rows[-1:]).splitlines()[-1], flush=True)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).with_suffix(".json").write_text(json.dumps(rows, indent=1))
    Path(args.out).with_suffix(".md").write_text(markdown(rows))


if __name__ == "__main__":
    main()
