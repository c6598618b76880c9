"""The downstream check, old vs new code, in one run (`make bench`, or alone: `.venv/bin/python benchmarks/downstream.py`).

Writes reports/bench/downstream.md and downstream.json. For each pose (a results folder with keyframes.h5 and
verify.h5; by default lion-01 and camel-01, which `make bench` repairs first): the whole grid of the downstream
check (posefix.downstream.check.GRID, alphas x k_bend, towards the original and the repaired pose) with the library of an older
revision (``--old``, exported with ``git archive``) and with this one, one run after the other, each in a fresh
process with one BLAS thread; this one also with 2 workers (downstream.threads). Wall and CPU seconds (the
workers' included), converged runs and iterations.
"""

import argparse
import hashlib
import json
import os
import resource
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

from posefix.downstream.check import GRID

ROOT = Path(__file__).resolve().parents[1]
OLD = "5302533"
"""The last revision with the CG-preconditioned solver (one ordering per factorization, serial grid)."""
POSES = ("results/lion-poses/lion-01", "results/camel-poses/camel-01")


def run_check(folder, workers, grid):
    """One downstream check of the pose in ``folder`` over ``grid`` (alphas, k_bend) with the importable posefix
    (dict, printed as JSON)."""
    import h5py
    from threadpoolctl import threadpool_limits

    from posefix.downstream.check import downstream_check

    with h5py.File(Path(folder) / "keyframes.h5", "r") as fh:
        V_ref, target, F = fh["reference"][()], fh["target"][()], fh["faces"][()]
    with h5py.File(Path(folder) / "verify.h5", "r") as fh:
        repaired = fh["repaired"][()]
    extra = {"workers": workers} if workers > 1 else {}
    with threadpool_limits(1):
        start, cpu = time.perf_counter(), time.process_time()
        check = downstream_check(V_ref, F, {"original": target, "repaired": repaired}, **grid, **extra)
        seconds = time.perf_counter() - start
    cpu = time.process_time() - cpu + resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime
    digest = hashlib.sha256(b"".join(r.V.tobytes() + r.errors.tobytes() for r in check.runs)).hexdigest()[:16]
    return {"vertices": len(V_ref), "seconds": seconds, "cpu_seconds": cpu, "metrics": check.metrics(),
            "runs": [[r.iterations, r.reason] for r in check.runs], "digest": digest}


def measure(folder, lib, workers):
    """:func:`run_check` in a fresh process importing posefix from ``lib``."""
    env = {**os.environ, "PYTHONPATH": str(lib)}
    out = subprocess.run([sys.executable, __file__, "--run", str(folder), "--workers", str(workers),
                          "--grid", json.dumps(GRID)], env=env,
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def export_lib(rev, into):
    """The ``lib`` folder of revision ``rev``, extracted under ``into``; its path."""
    archive = Path(into) / "lib.tar"
    with open(archive, "wb") as fh:
        subprocess.run(["git", "-C", str(ROOT), "archive", rev, "lib"], stdout=fh, check=True)
    with tarfile.open(archive) as tar:
        tar.extractall(into, filter="data")
    return Path(into) / "lib"


def markdown(rows, old):
    """The section of BENCHMARKS.md (list of str)."""
    lines = ["## Downstream check: old vs new solver", "",
             f"The whole grid (alphas x k_b, towards the original and the repaired pose) with the code of {old} "
             "(conjugate gradients preconditioned by the last LU, a new fill-reducing ordering per factorization) "
             "and with this one (one ordering per run, a direct step every iteration, the Jacobian's pattern built "
             "once), each in a fresh process with one BLAS thread; 'new, 2 workers': two runs of the grid at a time "
             "(downstream.threads 2). CPU seconds include the workers'.", "",
             "| pose | vertices | runs | old s (CPU) | new s (CPU) | old / new | new, 2 workers s | old / that | "
             "converged old / new | iterations old / new | 2 workers: same iterations / same bits |",
             "|---|---:|---:|---|---|---:|---:|---:|---|---|---|"]
    for r in rows:
        o, n, n2 = r["old"], r["new"], r["new2"]
        conv = lambda m: f"{m['original_converged']} + {m['repaired_converged']}"  # noqa: E731
        iters = lambda m: f"{m['original_iterations']} + {m['repaired_iterations']}"  # noqa: E731
        lines.append(f"| {r['pose']} | {n['vertices']:,} | {len(n['runs'])} | {o['seconds']:.1f} ({o['cpu_seconds']:.1f}) | "
                     f"{n['seconds']:.1f} ({n['cpu_seconds']:.1f}) | {o['seconds'] / n['seconds']:.2f} | "
                     f"{n2['seconds']:.1f} | {o['seconds'] / n2['seconds']:.2f} | {conv(o['metrics'])} / "
                     f"{conv(n['metrics'])} | {iters(o['metrics'])} / {iters(n['metrics'])} | "
                     f"{'yes' if n['runs'] == n2['runs'] else 'no'} / {'yes' if n['digest'] == n2['digest'] else 'no'} |")
    return lines + ["", "Converged and iterations: towards the original + towards the repaired pose. The new step is "
                    "exact where the old one was exact to 1e-10 (CG), so runs that end in a collapsed triangle may "
                    "move by a few iterations. 'Same bits': the final positions and energies of every run, with 2 workers as "
                    "with one (roundoff-sensitive runs, those ending in a collapsed triangle, can differ in the last "
                    "bits between processes).", ""]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--old", default=OLD, help="revision whose lib/ is the old code")
    parser.add_argument("--poses", nargs="*", default=[str(ROOT / p) for p in POSES],
                        help="results folders of poses (keyframes.h5, verify.h5)")
    parser.add_argument("--out", default=str(ROOT / "reports" / "bench"))
    parser.add_argument("--run", default=None, help=argparse.SUPPRESS)  # one check, in a child process
    parser.add_argument("--workers", type=int, default=1, help=argparse.SUPPRESS)
    parser.add_argument("--grid", type=json.loads, default=None, help=argparse.SUPPRESS)  # this revision's GRID
    args = parser.parse_args()
    if args.run:
        print(json.dumps(run_check(args.run, args.workers, args.grid)))
        return
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        old_lib = export_lib(args.old, tmp)
        for folder in map(Path, args.poses):
            if not (folder / "verify.h5").exists():
                print(f"skipping {folder}: no verify.h5 (run the pipeline first)", flush=True)
                continue
            row = {"pose": folder.name, "old": measure(folder, old_lib, 1), "new": measure(folder, ROOT / "lib", 1),
                   "new2": measure(folder, ROOT / "lib", 2)}
            print(f"{folder.name}: old {row['old']['seconds']:.1f} s, new {row['new']['seconds']:.1f} s, "
                  f"2 workers {row['new2']['seconds']:.1f} s", flush=True)
            rows.append(row)
    (out / "downstream.md").write_text("\n".join(markdown(rows, args.old)))
    (out / "downstream.json").write_text(json.dumps(rows, indent=1))
    print(f"wrote {out / 'downstream.md'}")


if __name__ == "__main__":
    main()
