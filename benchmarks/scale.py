"""S0 at production sizes (`make bench`, or alone: `.venv/bin/python benchmarks/scale.py`): reports/bench/scale.md.

Two parts, both in one run:

1. **Residual evaluation** of the greedy fit without its kernel cache, numpy (the reference: chunks of
   ``kernel_matrix @ weights``) against the OpenCL ``FieldEvaluator`` at 150k constraints x 4k centres,
   on one thread each (the fit rule's default), with the largest difference between the two.
2. **End to end** with ``snakemake --cores 2``: one camel pose (21.9k vertices) and one kids pose (59.7k
   vertices, ``0001.null.0.off.gz`` as reference) through verify, export and the one-setting downstream
   check of ``make run`` (no other repairs), per-stage seconds and peak memory (Snakemake's benchmark files),
   next to S0's goblin (86k vertices: 10k centres, 603 s fit on a GTX 460 + 4 cores). Snakemake reuses
   results that are up to date: delete ``results/<library>`` for fresh seconds.
"""

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from posefix.workflow.timings import benchmark_row

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSEFIX_DATA", ROOT.parent / "shared" / "data"))
CASES = {  # library folder -> (reference, pose)
    "camel-poses": ("camel-reference.obj.gz", "camel-01"),
    "kids-0001": ("0001.null.0.off.gz", "0001.isometry.1"),
}
STAGES = ("validate", "keyframes", "classify", "constraints", "fit", "integrate", "verify", "export", "downstream")
S0_GOBLIN = {"vertices": 86000, "centers": 10000, "fit_seconds": 603.0}
RUN_CONFIG = ["repairs=[]"]
EVALUATION = {"constraints": 150_000, "centers": 4000, "repeat": 3}


def evaluation_row(seed=0):
    """Seconds of one residual evaluation, numpy vs OpenCL, on random points in the normalized box (dict)."""
    os.environ["POCL_MAX_PTHREAD_COUNT"] = "1"  # before the OpenCL runtime starts: the fit rule's one thread
    from threadpoolctl import threadpool_limits

    from posefix.spacetime.integration_opencl import FieldEvaluator, select_device
    from posefix.spacetime.rbf import kernel_matrix, poly_basis

    rng = np.random.default_rng(seed)
    N, n = EVALUATION["constraints"], EVALUATION["centers"]
    Z = rng.uniform(-0.75, 0.75, size=(N, 4))
    C, w, p = Z[rng.choice(N, n, replace=False)], rng.normal(size=(n, 3)), rng.normal(size=(15, 3))

    def numpy_values():
        out = poly_basis(Z) @ p
        for start in range(0, N, 4096):
            out[start:start + 4096] += kernel_matrix(Z[start:start + 4096], C) @ w
        return out

    device, name = select_device("auto")
    with threadpool_limits(1):
        numpy_s, expected = _best_of(numpy_values)
    row = {"constraints": N, "centers": n, "numpy_seconds": numpy_s, "device": name}
    if device is not None:
        evaluator = FieldEvaluator(device, Z)
        evaluator(C, w, p)  # the first launch compiles for the work-group size
        row["opencl_seconds"], got = _best_of(lambda: evaluator(C, w, p))
        row["max_relative_difference"] = float(np.abs(got - expected).max() / np.abs(expected).max())
    return row


def _best_of(fn):
    best, out = np.inf, None
    for _ in range(EVALUATION["repeat"]):
        start = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - start)
    return best, out


def run_case(library, cores):
    """Run the pipeline on one pose of ``library``; per-stage seconds and peak MB, and the pose's summary."""
    reference, pose = CASES[library]
    cmd = [sys.executable, "-m", "snakemake", "--cores", str(cores), "--config", f"library={DATA / library}",
           f"reference={reference}", f"poses={pose}", *RUN_CONFIG]
    print("+", " ".join(cmd), flush=True)
    start = time.perf_counter()
    subprocess.run(cmd, cwd=ROOT, check=True)
    folder = ROOT / "results" / library / "benchmarks" / pose
    stages = {stage: _benchmark(folder, stage) for stage in STAGES}
    summary = json.loads((ROOT / "reports" / library / "summary.json").read_text())["poses"]
    return {"library": library, "pose": pose, "wall_seconds": time.perf_counter() - start, "stages": stages,
            "summary": next(p for p in summary if p["pose"] == pose)}


def _benchmark(folder, stage):
    """Seconds and max RSS (MB) of a stage from its Snakemake benchmark file, None when it did not run."""
    row = benchmark_row(folder, stage)
    if row is None:
        return None
    return {"seconds": float(row["s"]), "max_rss_mb": float(row["max_rss"]) if row["max_rss"] != "NA" else None}


def markdown(evaluation, cases, cores):
    """The section 'S0 at production sizes' of BENCHMARKS.md (list of str)."""
    lines = ["## S0 at production sizes", "",
             f"Residual evaluation of the fit without its kernel cache ({evaluation['constraints']:,} constraints x "
             f"{evaluation['centers']:,} centres, one thread each, best of {EVALUATION['repeat']}):", "",
             "| numpy s | OpenCL s | numpy / OpenCL | max relative difference | device |", "|---:|---:|---:|---:|---|"]
    if "opencl_seconds" in evaluation:
        lines.append(f"| {evaluation['numpy_seconds']:.2f} | {evaluation['opencl_seconds']:.3f} | "
                     f"{evaluation['numpy_seconds'] / evaluation['opencl_seconds']:.1f} | "
                     f"{evaluation['max_relative_difference']:.1e} | {evaluation['device']} |")
    else:
        lines.append(f"| {evaluation['numpy_seconds']:.2f} | - | - | - | {evaluation['device']} |")
    lines += ["", f"One pose end to end, `snakemake --cores {cores}` (no other repairs; downstream: the one setting of "
              "`make run`); seconds (peak MB) per stage from Snakemake's benchmark files:", "",
              "| library | pose | vertices | V_C | " + " | ".join(STAGES) + " | fit + integrate s | all stages s | "
              "centres | fit max error / d | integrated V_C max / d | new outside pass-through |",
              "|---|---|---:|---:|" + "---:|" * (len(STAGES) + 6)]
    for case in cases:
        s, p = case["stages"], case["summary"]
        cells = [f"{s[k]['seconds']:.0f} ({s[k]['max_rss_mb']:.0f})" if s[k] else "-" for k in STAGES]
        total = sum(v["seconds"] for v in s.values() if v)
        faces = p["intersecting_faces"]
        lines.append(
            f"| {case['library']} | {case['pose']} | {p['vertices']:,} | {p['constraint_vertices']:,} | "
            + " | ".join(cells) + f" | {s['fit']['seconds'] + s['integrate']['seconds']:.0f} | {total:.0f} | "
            f"{p['fit']['centers']} | {p['fit']['max_error_rel']:.1e} | "
            f"{p['integrated_deviation']['constrained_max']:.1e} | "
            f"{faces['repaired_new'] - faces['repaired_new_in_fallback']} |")
    lines += ["", f"S0's goblin ({S0_GOBLIN['vertices']:,} vertices): {S0_GOBLIN['centers']:,} centres, "
              f"{S0_GOBLIN['fit_seconds']:.0f} s fit on a GTX 460 + 4 cores.", ""]
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default=str(ROOT / "reports" / "bench"))
    parser.add_argument("--cores", type=int, default=2)
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    evaluation = evaluation_row()
    print(f"residual evaluation: {evaluation}", flush=True)
    cases = [run_case(lib, args.cores) for lib in CASES if (DATA / lib).is_dir()]
    (out / "scale.md").write_text("\n".join(markdown(evaluation, cases, args.cores)))
    (out / "scale.json").write_text(json.dumps({"evaluation": evaluation, "cases": cases}, indent=1))
    print(f"wrote {out / 'scale.md'}")


if __name__ == "__main__":
    main()
