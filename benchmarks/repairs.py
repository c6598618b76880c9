"""Repairs compared (`make bench`, or alone: `.venv/bin/python benchmarks/repairs.py`): reports/bench/repairs.md.

S0's space-time repair and the baseline repairs (config ``baselines: [medial, volumetric]``: S1's balls and
flow, S4's volumetric fill) on every pose of lion, cat and horse (../shared/data) and the demo library: the
pipeline runs with the downstream check towards every repaired pose (``downstream.baselines: true``;
Snakemake reuses what is up to date), then
one table from each library's summary.json: poses with no new intersecting face outside S0's pass-through
regions, deviation from the target over V_C and over the free vertices (relative to the bbox diagonal),
Gauss-Newton runs converged and their iterations, seconds per pose.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from posefix.pipeline.timings import benchmark_seconds
from posefix.report.tables import repair_seconds

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSEFIX_DATA", ROOT.parent / "shared" / "data"))
LIBRARIES = ("lion-poses", "cat-poses", "horse-poses")
CHECK_BASELINES = "downstream={'baselines': True}"


def run_library(lib, cores, out):
    """Run the pipeline on ``lib`` (None: the demo) with the check towards the baselines; its summary entries
    (its summary.md goes to ``out``/summary-<library>.md)."""
    name = lib.name if lib else "demo"
    config = [f"library={lib}"] if lib else []
    cmd = [sys.executable, "-m", "snakemake", "--cores", str(cores), "--config", *config, CHECK_BASELINES]
    print("+", " ".join(cmd), flush=True)
    subprocess.run(cmd, cwd=ROOT, check=True)
    shutil.copyfile(ROOT / "reports" / name / "summary.md", out / f"summary-{name}.md")
    return json.loads((ROOT / "reports" / name / "summary.json").read_text())["poses"]


def gauss_newton(downstream, example):
    """(converged runs, runs, iterations of all runs) of one example over the whole grid of a pose."""
    runs = [per[example] for per in downstream["alphas"].values()]
    converged = sum(sum(r["converged"]) for r in runs)
    return converged, sum(len(r["converged"]) for r in runs), sum(sum(r["iterations"]) for r in runs)


BASELINES = ("medial", "volumetric")
LIBRARY_STAGES = {"medial": "skeleton", "volumetric": "tet_mesh"}
"""The once-per-library stage of each baseline (its seconds are reported apart)."""


def method_rows(entries):
    """Per method (S0, then each baseline): the figures of one library over its poses (dict of dicts)."""
    s0 = [{"clean": e["intersecting_faces"]["repaired_new"] == e["intersecting_faces"]["repaired_new_in_fallback"],
           "new": e["intersecting_faces"]["repaired_new"], "deviation": e["deviation"], "seconds": repair_seconds(e),
           "gn": gauss_newton(e["downstream"], "repaired"), "gn_target": gauss_newton(e["downstream"], "original")}
          for e in entries]
    rows = {"S0": _aggregate(s0)}
    for name in BASELINES:
        rows[name] = _aggregate([{"clean": b["intersecting_faces"]["repaired_new"] == 0,
                                  "new": b["intersecting_faces"]["repaired_new"], "deviation": b["deviation"],
                                  "seconds": b["seconds"],
                                  "gn": gauss_newton(b["downstream"], name) if "downstream" in b else None}
                                 for b in (e["baselines"][name] for e in entries)])
    rows["target"] = {"gn": np.sum([r["gn_target"] for r in s0], axis=0).tolist()}
    return rows


def _aggregate(rows):
    dev = [r["deviation"] for r in rows]
    gn = [r["gn"] for r in rows if r["gn"] is not None]
    return {"poses": len(rows), "clean": sum(r["clean"] for r in rows), "new_faces": sum(r["new"] for r in rows),
            "vc_mean": float(np.mean([d["constrained_mean"] for d in dev])),
            "vc_max": float(max(d["constrained_max"] for d in dev)),
            "free_max": float(max(d["free_max"] for d in dev)),
            "gn": np.sum(gn, axis=0).tolist() if len(gn) == len(rows) else None,
            "seconds": float(np.mean([r["seconds"] for r in rows]))}


def markdown(result):
    """The section 'Repairs compared' of BENCHMARKS.md (list of str)."""
    lines = ["## Repairs compared: S0 vs the medial repair (S1) and the volumetric fill (S4)", "",
             "Every pose of each library, the three repairs from the same target (`benchmarks/repairs.py`, which also "
             "runs alone). Per pose: `summary-<library>.md`, section 'S0 vs the baseline repairs'.", "",
             "| library | repair | poses | 0 new faces (S0: outside pass-through) | new faces (all poses) | "
             "V_C deviation mean (mean over poses) | V_C max | free max | GN converged / runs | GN iterations "
             "(all runs) | seconds per pose |", "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name, r in result["libraries"].items():
        for method in ("S0", *BASELINES):
            m = r[method]
            gn = f"{m['gn'][0]} / {m['gn'][1]} | {m['gn'][2]}" if m["gn"] else "- | -"
            lines.append(f"| {name} | {method} | {m['poses']} | {m['clean']} | {m['new_faces']} | {m['vc_mean']:.1e} | "
                         f"{m['vc_max']:.1e} | {m['free_max']:.1e} | {gn} | {m['seconds']:.1f} |")
        t = r["target"]["gn"]
        lines.append(f"| {name} | (target, unrepaired) | | | | | | | {t[0]} / {t[1]} | {t[2]} | |")
    lines += ["", "Deviations are from the target, relative to the reference's bbox diagonal, over S0's V_C (classify) "
                  "and the other (free) vertices. GN: the downstream Gauss-Newton check (S0 §5) over config "
                  "downstream's grid towards each pose. Seconds: wall seconds of the stages per pose (S0: keyframes "
                  "to verify; medial: repair_medial; volumetric: repair_volumetric), without the stages each baseline "
                  "runs once per library (medial: skeleton; volumetric: tet_mesh): "
              + ", ".join(f"{n} {r['library_seconds']['skeleton']:.1f} s and {r['library_seconds']['tet_mesh']:.1f} s"
                          for n, r in result["libraries"].items()) + ".", ""]
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", default=str(ROOT / "reports" / "bench"))
    parser.add_argument("--cores", type=int, default=2)
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    libraries = [DATA / n for n in LIBRARIES if (DATA / n).is_dir()] + [None]
    result = {"libraries": {}}
    for lib in libraries:
        name = lib.name if lib else "demo"
        rows = method_rows(run_library(lib, args.cores, out))
        rows["library_seconds"] = {stage: benchmark_seconds(ROOT / "results" / name / "benchmarks", stage) or 0.0
                                   for stage in LIBRARY_STAGES.values()}
        result["libraries"][name] = rows
    result["seconds"] = time.perf_counter() - start
    (out / "repairs.md").write_text("\n".join(markdown(result)))
    (out / "repairs.json").write_text(json.dumps(result, indent=1))
    print(f"wrote {out / 'repairs.md'}")


if __name__ == "__main__":
    main()
