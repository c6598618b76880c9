"""`make bench`: run the pipeline on the benchmark libraries and collect the benchmarks in reports/bench/.

Libraries: lion, cat and horse poses from ../shared/data (the demo library when that folder is
absent, which the report says). Pieces: the self-intersection detector against pymeshlab
(benchmarks/detector.py) on every key frame, the RBF fit variants on the first pose with the scipy
peer check (benchmarks/fit.py), the OpenCL integration of every lion pose against numpy on two
(benchmarks/integrate.py), the repair and the downstream check (each library's summary.json), S1's skeletal
deformation next to S1 Fig. 12-13 (benchmarks/skeletal.py, which also runs alone), S0 vs the medial
repair and the volumetric fill on every pose (benchmarks/repairs.py, which also runs alone; the pipeline runs
with the downstream check towards every repair), S4's volumetric editing and transfer next to S4 Table 3.1
(benchmarks/volumetric.py, which also runs alone) and S4's marker animation against the horse gallop
(benchmarks/markers.py, which also runs alone) where the integrated field's V_C error comes from (benchmarks/accuracy.py, from the
pipeline's results) and S0 at production sizes, one camel and one kids pose end to end (benchmarks/scale.py,
which also runs alone), ipctk's broad phases on the contact solver's queries (benchmarks/broad_phase.py, which also
runs alone), the downstream check's old vs new solver on lion-01 and camel-01 (benchmarks/downstream.py,
which also runs alone), and USD and glTF libraries against folders of mesh files (benchmarks/containers.py, which
also runs alone), and a 59-pose library (horse-poses and horse-gallop) end to end with every repair, per stage and
per pose (benchmarks/library.py, which also runs alone). Everything is collected into
``BENCHMARKS.md`` and ``BENCHMARKS.json`` (plus ``blocked_vs_full.png``) next to the per-library
pieces (``summary-<library>.md``: the library's per-pose summary), with the hand-written prose of
``benchmarks/notes.md`` in place; the same command on the same data gives the same tables, times aside.
"""

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from threadpoolctl import threadpool_info

from posefix.report.tables import downstream_grid_markdown, downstream_markdown
from notes import with_notes  # benchmarks/notes.py beside: the hand-written prose of benchmarks/notes.md
from repairs import CHECK_REPAIRS, KEEP_INTERMEDIATES  # benchmarks/repairs.py beside: the same pipeline call

ROOT = Path(__file__).resolve().parents[1]

DATA = Path(os.environ.get("POSEFIX_DATA", ROOT.parent / "shared" / "data"))
LIBRARIES = ("lion-poses", "cat-poses", "horse-poses")
S0_TABLE_1 = {  # S0 Table 1: GTX 460 + 4-core Phenom II, averages over the poses; S0 reached eps = 1e-4 d
    "lion-poses": {"centers": 2700, "max_condition": 2e6, "seconds": 13.0},
    "cat-poses": {"centers": 4500, "max_condition": 2e7, "seconds": 42.0},
    "horse-poses": {"centers": 4600, "max_condition": 7e6, "seconds": 43.0},
}


def machine():
    """What the numbers ran on: CPU model, cores, Python, BLAS libraries, OpenCL device (dict of str)."""
    model = platform.processor() or platform.machine()
    try:
        model = next(line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                     if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    blas = ", ".join(sorted({f"{i.get('internal_api')} {i.get('version')} ({i.get('threading_layer', '-')})"
                             for i in threadpool_info() if i.get("user_api") == "blas"})) or "unknown"
    from posefix.spacetime.integration_opencl import select_device
    device, name = select_device("auto")
    return {"cpu": model, "cores": str(os.cpu_count()), "python": platform.python_version(),
            "numpy": np.__version__, "blas": blas, "opencl": name if device is not None else f"none ({name})"}


def run(*args, **kwargs):
    """Run a command (list of str) from the project root, echoing it; fails loudly."""
    print("+", " ".join(map(str, args)), flush=True)
    subprocess.run([str(a) for a in args], cwd=ROOT, check=True, **kwargs)


def bench_library(lib, out, cores):
    """Pipeline and the benchmark pieces of one library (None: the demo); returns their JSON."""
    name = lib.name if lib else "demo"
    start = time.perf_counter()
    run(sys.executable, "-m", "snakemake", "--cores", cores, "--config", *([f"library={lib}"] if lib else []),
        KEEP_INTERMEDIATES, CHECK_REPAIRS)
    pipeline_s = time.perf_counter() - start
    results = ROOT / "results" / name
    pieces = {"pipeline_seconds": pipeline_s,
              "summary": json.loads((ROOT / "reports" / name / "summary.json").read_text())["poses"]}
    shutil.copyfile(ROOT / "reports" / name / "summary.md", out / f"summary-{name}.md")
    run(sys.executable, ROOT / "benchmarks" / "detector.py", "--results", results, "--out", out / f"detector-{name}",
        "--repeat", 2)
    run(sys.executable, ROOT / "benchmarks" / "fit.py", "--library", name, "--results", results,
        "--out", out / f"fit-{name}", "--variant-poses", 1)
    for piece in ("detector", "fit"):
        pieces[piece] = json.loads((out / f"{piece}-{name}.json").read_text())
    if name in ("lion-poses", "demo"):
        run(sys.executable, ROOT / "benchmarks" / "integrate.py", "--library", name, "--results", results,
            "--out", out / f"integrate-{name}", "--numpy-poses", 2)
        pieces["integrate"] = json.loads((out / f"integrate-{name}.json").read_text())
    return pieces


def blocked_vs_full_figure(benchmarks):
    """Seconds per iteration (update + solve) against centres, blocked vs full, one line per library."""
    fig = Figure(figsize=(7, 4.2), dpi=110)
    ax = fig.add_subplot(1, 1, 1)
    for (name, pieces), color in zip(benchmarks.items(), ("tab:blue", "tab:orange", "tab:green", "tab:red")):
        timing = pieces["fit"]["iteration_seconds"]
        for update, style in (("blocked", "-"), ("full", "--")):
            points = sorted(timing.get(update, []))
            if points:
                c, s = np.array(points).T
                centres = np.unique(c)
                ax.plot(centres, [np.median(s[c == x]) for x in centres], style, color=color, label=f"{name}, {update}")
    ax.set_xlabel("centres")
    ax.set_ylabel("seconds per iteration (update + solve)")
    ax.set_yscale("log")
    ax.set_title("Factorization update: blocked Cholesky vs full LU (S0 Fig. 5)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def fit_table(benchmarks):
    """Markdown rows: our defaults per library next to S0 Table 1."""
    lines = ["| library | source | poses | centres (mean) | max kappa | max error / d (mean) | fit s (mean) |",
             "|---|---|---:|---:|---:|---:|---:|"]
    for name, pieces in benchmarks.items():
        rows = [r for r in pieces["fit"]["rows"] if (r["selection"], r["update"]) == ("fps", "blocked")]
        paper = S0_TABLE_1.get(name)
        if paper:
            lines.append(f"| {name} | S0 Table 1 (GTX 460) | | {paper['centers']} | {paper['max_condition']:.0e} | "
                         f"< 1e-4 | {paper['seconds']:.0f} |")
        lines.append(f"| {name} | posefix (this machine) | {len(rows)} | {np.mean([r['centers'] for r in rows]):.0f} | "
                     f"{max(r['max_condition'] for r in rows):.1e} | {np.mean([r['max_error_rel'] for r in rows]):.1e} | "
                     f"{np.mean([r['seconds'] for r in rows]):.1f} |")
    return lines


def repair_table(benchmarks):
    """Markdown rows: what the repair achieved per library (from summary.json)."""
    lines = ["| library | poses | pipeline s (all poses) | new = 0 | new outside pass-through = 0 | "
             "V_C max <= 5e-3 | V_C mean (max over poses) | fit s (mean) | integrate s (mean) |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name, pieces in benchmarks.items():
        poses = pieces["summary"]
        faces = [p["intersecting_faces"] for p in poses]
        lines.append(
            f"| {name} | {len(poses)} | {pieces['pipeline_seconds']:.0f} | "
            f"{sum(f['repaired_new'] == 0 for f in faces)} | "
            f"{sum(f['repaired_new'] == f['repaired_new_in_fallback'] for f in faces)} | "
            f"{sum(p['deviation']['constrained_max'] <= 5e-3 for p in poses)} | "
            f"{max(p['deviation']['constrained_mean'] for p in poses):.1e} | "
            f"{np.mean([p['fit']['seconds'] for p in poses]):.1f} | "
            f"{np.mean([p['integrate']['seconds'] for p in poses]):.2f} |")
    return lines


def detector_table(benchmarks):
    lines = ["| library | frames | posefix ms / frame | pymeshlab ms / frame | posefix / pymeshlab |", "|---|---:|---:|---:|---:|"]
    for name, pieces in benchmarks.items():
        rows = pieces["detector"]["rows"]
        frames = sum(r["frames"] for r in rows)
        ours, peer = sum(r["posefix_seconds"] for r in rows), sum(r["pymeshlab_seconds"] for r in rows)
        lines.append(f"| {name} | {frames} | {1000 * ours / frames:.1f} | {1000 * peer / frames:.1f} | {ours / peer:.2f} |")
    return lines


def downstream_section(benchmarks):
    """Markdown lines: the downstream check per library and per setting (from summary.json)."""
    lines = ["## Downstream check: Gauss-Newton discrete shells, original vs repaired (S0 §5)", "",
             "Per library (all poses, every setting of the grid):", "",
             "| library | runs per example | converged original | converged repaired | iterations original / "
             "repaired (all runs) | both converged | their iterations original / repaired | fewer |",
             "|---|---:|---:|---:|---|---:|---|---:|"]
    for name, pieces in benchmarks.items():
        row = downstream_markdown(pieces["summary"])[-1].split(" | ", 1)[1]  # the "all" row (or the one pose)
        lines.append(f"| {name} | {row}")
    entries = [e for pieces in benchmarks.values() for e in pieces["summary"]]
    return lines + ["", "Per setting (all libraries):", "", *downstream_grid_markdown(entries), "",
                    "Converged: energy zero, or a full step accepted with |J^T r| reduced 1e4-fold; 'fewer': the "
                    "iteration reduction where both converged (S0: up to 60 %). Per pose: `summary-<library>.md`.", ""]


def report(info, benchmarks, note, out):
    """BENCHMARKS.md text, with its notes (benchmarks/notes.md)."""
    lines = ["# posefix benchmarks", "", COMMAND + note, "",
             "## Machine", "", *[f"- {k}: {v}" for k, v in info.items()], "",
             "## Repair (S0 pipeline end to end)", "", *repair_table(benchmarks), "",
             "Counts are poses. 'new': faces intersecting in the repaired pose but not in the reference; "
             "pass-through: regions copied from the target where key frames pass through each other (S0 Fig. 9). "
             "Per pose: `reports/<library>/summary.md`.", "",
             "## RBF fit next to S0 Table 1", "", *fit_table(benchmarks), "",
             "S0 stopped at eps = 1e-4 d; our fits stop at `fit.max_centers` (4000) with the max error in the "
             "table (reports/bench/fit-defaults-*.md: why). Per-library details, variants (full LU, worst-m "
             "selection) and the scipy peer check: `fit-<library>.md`.", "",
             "![blocked vs full](blocked_vs_full.png)", ""]
    for name in benchmarks:
        kept = [line for line in (out / f"fit-{name}.md").read_text().splitlines()
                if line.startswith(("| centres", "|---:|---:|---:|---:|", "| 1000", "| 2000", "| 3000", "Peer check"))]
        table, peer = [k for k in kept if k.startswith("|")], [k for k in kept if not k.startswith("|")]
        lines += [f"### {name}: blocked vs full per iteration, scipy peer", "", *table, "", *peer, ""]
    lines += ["## Integration backends", ""]
    for name, pieces in benchmarks.items():
        if "integrate" in pieces:
            lines += (out / f"integrate-{name}.md").read_text().splitlines()[2:] + [""]
    lines += downstream_section(benchmarks)
    lines += ["## Self-intersection detector vs pymeshlab", "", *detector_table(benchmarks), "",
              "Ours is exact (filtered orient3d with an exact fallback); pymeshlab's is floating point. "
              "Per pose: `detector-<library>.md`.", ""]
    lines += (out / "skeletal.md").read_text().splitlines() + [""]
    lines += (out / "repairs.md").read_text().splitlines() + [""]
    lines += (out / "vc-exact.md").read_text().splitlines() + [""]
    lines += (out / "volumetric.md").read_text().splitlines() + [""]
    if (out / "markers.md").exists():  # horse-gallop present
        lines += (out / "markers.md").read_text().splitlines() + [""]
    lines += (out / "accuracy.md").read_text().splitlines() + [""]
    lines += (out / "scale.md").read_text().splitlines() + [""]
    lines += (out / "broad-phase.md").read_text().splitlines() + [""]
    lines += (out / "downstream.md").read_text().splitlines() + [""]
    lines += (out / "containers.md").read_text().splitlines() + [""]
    if (out / "library.md").exists():  # horse-poses and horse-gallop present
        lines += (out / "library.md").read_text().splitlines() + [""]
    return with_notes("\n".join(lines), "BENCHMARKS.md")


COMMAND = "Command: `make bench` (benchmarks/run.py). "
"""The start of BENCHMARKS.md's first line; the run's note follows."""


def collect(out):
    """Write BENCHMARKS.md again from BENCHMARKS.json and the pieces in ``out`` (Path), after a piece ran alone
    (e.g. ``benchmarks/repairs.py``), running nothing; the note of the last full run is kept."""
    saved = json.loads((out / "BENCHMARKS.json").read_text())
    page = out / "BENCHMARKS.md"
    note = saved.get("note") or next((line[len(COMMAND):] for line in page.read_text().splitlines()
                                      if line.startswith(COMMAND)), "")
    page.write_text(report(saved["machine"], saved["libraries"], note, out))
    print(f"wrote {page} from the pieces in {out}")


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--out", default=str(ROOT / "reports" / "bench"))
    parser.add_argument("--collect", action="store_true",
                        help="write BENCHMARKS.md again from BENCHMARKS.json and the pieces in --out, running nothing "
                             "(after a piece ran alone)")
    args = parser.parse_args()
    if args.collect:
        return collect(Path(args.out))
    libraries = [DATA / name for name in LIBRARIES if (DATA / name).is_dir()]
    note = ("" if libraries else f"{DATA} is absent: this ran on the built-in demo library only.")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    benchmarks = {(lib.name if lib else "demo"): bench_library(lib, out, str(args.cores)) for lib in libraries or [None]}
    info = machine()
    blocked_vs_full_figure(benchmarks).savefig(out / "blocked_vs_full.png", metadata={"Software": None})
    run(sys.executable, ROOT / "benchmarks" / "skeletal.py", "--out", out, "--threads", args.cores)
    run(sys.executable, ROOT / "benchmarks" / "repairs.py", "--out", out, "--cores", args.cores)
    run(sys.executable, ROOT / "benchmarks" / "vc_exact.py", "--out", out)  # on repairs.py's results
    run(sys.executable, ROOT / "benchmarks" / "volumetric.py", "--out", out, "--threads", args.cores)
    run(sys.executable, ROOT / "benchmarks" / "markers.py", "--out", out, "--threads", args.cores)
    run(sys.executable, ROOT / "benchmarks" / "accuracy.py", "--out", out)
    run(sys.executable, ROOT / "benchmarks" / "scale.py", "--out", out, "--cores", args.cores)
    run(sys.executable, ROOT / "benchmarks" / "broad_phase.py", "--out", out)
    run(sys.executable, ROOT / "benchmarks" / "downstream.py", "--out", out)  # lion-01, and camel-01 from scale.py
    run(sys.executable, ROOT / "benchmarks" / "containers.py", "--out", out, "--cores", args.cores)
    run(sys.executable, ROOT / "benchmarks" / "library.py", "--out", out, "--cores", args.cores)
    note += f" Wall time of the whole benchmark: {(time.perf_counter() - start) / 60:.1f} min."
    (out / "BENCHMARKS.md").write_text(report(info, benchmarks, note.strip(), out))
    (out / "BENCHMARKS.json").write_text(json.dumps({"machine": info, "libraries": benchmarks, "note": note.strip()},
                                                    indent=1))
    print(f"wrote {out / 'BENCHMARKS.md'} and {out / 'BENCHMARKS.json'}")


if __name__ == "__main__":
    main()
