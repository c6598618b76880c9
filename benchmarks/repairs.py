"""Repairs compared (`make bench`, or alone: `.venv/bin/python benchmarks/repairs.py`): reports/bench/repairs.md.

Five repairs of every pose of lion, cat, horse and camel (../shared/data) and the demo library, from the same
targets: space-time integration (S0) with the contact finish's elastic and positional goals (config
``verify.free_goal``: elastic, the default, and blend), the medial repair (S1's balls and flow), the volumetric fill
(S4's editor) and the contact repair (the IPC contact solver through S0's key frames). The pipeline runs twice per
library in one go: with the elastic finish and every other repair (results/<library>), then with the positional finish
alone (results/<library>-positional-finish, from the first run's artifacts up to integrate), the downstream check
towards every repaired pose both times
(``downstream.repairs: true``; Snakemake reuses what is up to date; ``--quick-downstream``: the default one setting,
alpha 1 and k_b 1e-2, instead of the grid). One table from the summary.json files:
poses with no new intersecting face, poses "ok" (the report's status), deviation from the target over V_C and
over the free vertices (relative
to the bbox diagonal), the worst edge-length and area ratios against the target and the distorted faces,
Gauss-Newton runs converged and their iterations, seconds per pose.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from posefix.downstream.check import GRID
from posefix.workflow.timings import benchmark_seconds
from posefix.report.tables import entry_status, repair_seconds

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSEFIX_DATA", ROOT.parent / "shared" / "data"))
LIBRARIES = ("lion-poses", "cat-poses", "horse-poses", "camel-poses")
CHECK_REPAIRS = f"downstream={ {'repairs': True, **GRID} }"
"""The downstream check towards every repair over the grid of six settings (``make bench``)."""
QUICK_DOWNSTREAM = "downstream={'repairs': True}"
ELASTIC_FINISH = "verify={'finish': 'contact', 'free_goal': 'elastic'}"
POSITIONAL_FINISH = ("verify={'finish': 'contact', 'free_goal': 'blend'}", "repairs=[]")
"""The second run of a library: S0 with the positional finish, no other repairs (they are the first run's)."""
SUFFIX = "-positional-finish"
KEEP_INTERMEDIATES = "keep_intermediates=true"
"""The benchmarks of the fit and of the integrated field's accuracy read each pose's constraints.h5."""


def run_library(lib, cores, out, extra=(CHECK_REPAIRS,), suffix=""):
    """Run the pipeline on ``lib`` (None: the demo) with the ``extra`` config (the check towards the other repairs),
    results under <library><suffix>; its summary entries (its summary.md goes to ``out``)."""
    name = (lib.name if lib else "demo") + suffix
    config = ([f"library={lib}"] if lib else []) + ([f"name={name}"] if suffix else [])
    cmd = [sys.executable, "-m", "snakemake", "--cores", str(cores), "--config", *config, KEEP_INTERMEDIATES, *extra]
    print("+", " ".join(cmd), flush=True)
    subprocess.run(cmd, cwd=ROOT, check=True)
    shutil.copyfile(ROOT / "reports" / name / "summary.md", out / f"summary-{name}.md")
    return json.loads((ROOT / "reports" / name / "summary.json").read_text())["poses"]


UPSTREAM = ("validate", "keyframes", "classify", "constraints", "fit", "integrate")
"""S0's stages before verify: the positional run takes them from the elastic run (same inputs, same config)."""


def seed_second_run(name, suffix):
    """Copy S0's upstream artifacts and benchmark files of results/<name> into results/<name><suffix>, with their
    times, where missing or older: the positional run then computes verify and what follows only."""
    source, dest = ROOT / "results" / name, ROOT / "results" / (name + suffix)
    files = [source / "reference.h5"] + [f for stage in UPSTREAM for f in source.glob(f"*/{stage}.h5")]
    files += [f for stage in UPSTREAM for f in (source / "benchmarks").glob(f"*/{stage}.tsv")]
    for f in files:
        target = dest / f.relative_to(source)
        if not target.exists() or target.stat().st_mtime < f.stat().st_mtime:
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(f, target)


def finish_seconds(name, poses):
    """Wall seconds of stage verify per pose with each finish, one process at a time on the same artifacts of
    results/<name> (the pipeline runs jobs side by side, so its own benchmark files mix in their contention):
    {pose: {"elastic": s, "positional": s}}."""
    out = {}
    for pose in poses:
        folder = ROOT / "results" / name / pose
        inputs = [f"--{k}={folder / f'{k}.h5'}" for k in ("keyframes", "classify", "integrate", "fit")]
        out[pose] = {}
        for finish, goal in (("elastic", "elastic"), ("positional", "blend")):
            with tempfile.TemporaryDirectory() as tmp:
                start = time.perf_counter()
                subprocess.run([sys.executable, str(ROOT / "stages" / "verify.py"), *inputs, "--free-goal", goal,
                                "--threads", "1", "--out", str(Path(tmp) / "verify.h5")], check=True,
                               capture_output=True)
                out[pose][finish] = time.perf_counter() - start
    return out


def finish_markdown(result):
    """The table of :func:`finish_seconds` with S0's other stages added (list of str)."""
    lines = ["", "### Seconds per pose: the elastic finish against the positional finish", "",
             "Stage verify alone, one process at a time on the same artifacts (`--threads 1`), plus S0's stages "
             "keyframes to integrate (the pipeline's benchmark files of the elastic run).", "",
             "| library | pose | keyframes to integrate s | verify elastic s | verify positional s | S0 elastic s "
             "| S0 positional s | ratio |", "|---|---|---:|---:|---:|---:|---:|---:|"]
    for name, r in result["libraries"].items():
        for pose, t in r["finish_seconds"].items():
            before = r["upstream_seconds"][pose]
            lines.append(f"| {name} | {pose} | {before:.1f} | {t['elastic']:.1f} | {t['positional']:.1f} | "
                         f"{before + t['elastic']:.1f} | {before + t['positional']:.1f} | "
                         f"{(before + t['elastic']) / (before + t['positional']):.2f} |")
    return lines + [""]


def gauss_newton(downstream, example):
    """(converged runs, runs, iterations of all runs) of one example over the whole grid of a pose."""
    runs = [per[example] for per in downstream["alphas"].values()]
    converged = sum(sum(r["converged"]) for r in runs)
    return converged, sum(len(r["converged"]) for r in runs), sum(sum(r["iterations"]) for r in runs)


OTHER_REPAIRS = ("medial", "volumetric", "contact")
LIBRARY_STAGES = {"medial": "skeleton", "volumetric": "tet_mesh"}
"""The once-per-library stage of another repair (its seconds are reported apart)."""
REPAIRS = ("space-time, elastic finish", "space-time, positional finish", *OTHER_REPAIRS)


def method_rows(elastic, positional):
    """Per repair of :data:`REPAIRS`: the figures of one library over its poses (dict of dicts); ``elastic`` and
    ``positional``: the summary entries of the two runs (the other repairs are the first's)."""
    rows = {finish: _aggregate([_s0_row(e) for e in entries]) for finish, entries in
            zip(REPAIRS[:2], (elastic, positional))}
    for name in OTHER_REPAIRS:
        rows[name] = _aggregate([{"clean": b["intersecting_faces"]["repaired_new"] == 0, "ok": None,
                                  "new": b["intersecting_faces"]["repaired_new"], "deviation": b["deviation"],
                                  "distortion": b.get("distortion"), "seconds": b["seconds"],
                                  "gn": gauss_newton(b["downstream"], name) if "downstream" in b else None}
                                 for b in (e["repairs"][name] for e in elastic)])
    rows["target"] = {"gn": np.sum([gauss_newton(e["downstream"], "original") for e in elastic], axis=0).tolist()}
    for finish, entries in zip(REPAIRS[:2], (elastic, positional)):
        rows[finish]["stretched_where_peer_not"] = stretched_where_peer_is_not(entries, elastic)
    return rows


def stretched_where_peer_is_not(entries, peer_entries, limit=4.0):
    """Poses whose repair has a face with an edge ratio beyond ``limit`` against both the target and the
    reference (``edge_nearest``) where the contact peer's repair of the same pose has none (int)."""
    peer = {e["pose"]: e["repairs"]["contact"].get("distortion") for e in peer_entries}
    return sum(1 for e in entries if e.get("distortion") and peer.get(e["pose"])
               and e["distortion"]["edge_nearest"] > limit >= peer[e["pose"]]["edge_nearest"])


def _s0_row(e):
    faces = e["intersecting_faces"]
    return {"clean": faces["repaired_new"] == faces["repaired_new_in_fallback"], "new": faces["repaired_new"],
            "ok": entry_status(e)[0] == "ok", "deviation": e["deviation"], "distortion": e.get("distortion"),
            "seconds": repair_seconds(e), "gn": gauss_newton(e["downstream"], "repaired")}


def _aggregate(rows):
    dev, dist = [r["deviation"] for r in rows], [r["distortion"] for r in rows if r["distortion"]]
    gn = [r["gn"] for r in rows if r["gn"] is not None]
    oks = [r["ok"] for r in rows if r["ok"] is not None]
    return {"poses": len(rows), "clean": sum(r["clean"] for r in rows), "new_faces": sum(r["new"] for r in rows),
            "ok": sum(oks) if oks else None,
            "vc_mean": float(np.mean([d["constrained_mean"] for d in dev])),
            "vc_max": float(max(d["constrained_max"] for d in dev)),
            "free_mean": float(np.mean([d["free_mean"] for d in dev])),
            "free_max": float(max(d["free_max"] for d in dev)),
            "edge": float(max(d["edge_target"] for d in dist)) if dist else None,
            "edge_nearest": float(max(d["edge_nearest"] for d in dist)) if dist else None,
            "area": float(max(d["area_target"] for d in dist)) if dist else None,
            "distorted": sum(d["faces_over"] for d in dist) if dist else None,
            "gn": np.sum(gn, axis=0).tolist() if len(gn) == len(rows) else None,
            "seconds": float(np.mean([r["seconds"] for r in rows]))}


def markdown(result):
    """The section 'Repairs compared' of BENCHMARKS.md (list of str)."""
    lines = ["## Repairs compared: space-time (elastic and positional finish), medial, volumetric, contact", "",
             "Every pose of each library, the five repairs from the same target (`benchmarks/repairs.py`, which also "
             "runs alone). Per pose: `summary-<library>.md` (elastic finish and the other repairs) and "
             f"`summary-<library>{SUFFIX}.md`." + (" Downstream check: one setting (alpha 1, k_b 1e-2)."
                                                      if result["quick_downstream"] else ""), "",
             "| library | repair | poses | 0 new faces | new faces (all poses) | ok | "
             "V_C dev. mean (mean over poses) | V_C max | free mean | free max | worst edge / area ratio | worst edge ratio, "
             "target or reference | poses beyond 4 where the peer is not | distorted "
             "faces | GN converged / runs | GN iterations (all runs) | seconds per pose |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|"]
    for name, r in result["libraries"].items():
        for method in REPAIRS:
            lines.append(_markdown_row(name, method, r[method]))
        t = r["target"]["gn"]
        lines.append(f"| {name} | (target, unrepaired) | | | | | | | | | | | | | {t[0]} / {t[1]} | {t[2]} | |")
    lines += ["", "Deviations are from the target, relative to the reference's bbox diagonal, over S0's V_C (classify) "
                  "and the other (free) vertices. ok: the report's status (no new intersecting face outside the "
                  "pass-through regions, V_C max within 1e-3, a converged finish, no face beyond 10x and at most 0.1% "
                  "beyond the distortion limit; S0 only). Ratios: the worst "
                  "edge-length and face-area ratio (or its inverse) against the target over all poses; target or "
                  "reference: the worst face's edge ratio against the nearer of the two (a face the target crushes "
                  "and a repair keeps near the reference is not stretched); poses beyond 4 where the peer is not: "
                  "S0's poses with an edge ratio beyond 4 against both where the contact repair's has none; distorted: "
                  "faces beyond config summary.distortion_limit against both the target and the reference. GN: the "
                  "downstream Gauss-Newton check (S0 §5) over config downstream's grid towards each pose. Seconds: "
                  "wall seconds of the stages per pose (S0: keyframes to verify; another repair: its repair stage), "
                  "without the stages another repair runs once per library (medial: skeleton; volumetric: tet_mesh): "
              + ", ".join(f"{n} {r['library_seconds']['skeleton']:.1f} s and {r['library_seconds']['tet_mesh']:.1f} s"
                          for n, r in result["libraries"].items()) + ". Measured at commit: "
              + ", ".join(f"{n} {r.get('commit', '?')}" for n, r in result["libraries"].items()) + ".", ""]
    return lines


def _markdown_row(library, method, m):
    gn = f"{m['gn'][0]} / {m['gn'][1]} | {m['gn'][2]}" if m["gn"] else "- | -"
    ratios = f"{m['edge']:.3g} / {m['area']:.3g}" if m["edge"] is not None else "-"
    ratios += f" | {m['edge_nearest']:.3g}" if m.get("edge_nearest") is not None else " | -"
    ratios += f" | {m.get('stretched_where_peer_not', '-')}"
    return (f"| {library} | {method} | {m['poses']} | {m['clean']} | {m['new_faces']} | "
            f"{'-' if m['ok'] is None else m['ok']} | {m['vc_mean']:.1e} | {m['vc_max']:.1e} | {m['free_mean']:.1e} | "
            f"{m['free_max']:.1e} | {ratios} | {'-' if m['distorted'] is None else m['distorted']} | {gn} | "
            f"{m['seconds']:.1f} |")


def _previous(path, quick_downstream):
    """The result of an earlier run at ``path`` when it checked downstream the same way (a run of some libraries
    replaces their rows and keeps the others'), else an empty one."""
    result = {"libraries": {}, "quick_downstream": quick_downstream}
    if path.exists():
        previous = json.loads(path.read_text())
        if previous.get("quick_downstream") == quick_downstream:
            result["libraries"] = previous["libraries"]
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", default=str(ROOT / "reports" / "bench"))
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--libraries", default=",".join(LIBRARIES + ("demo",)),
                        help="comma-separated libraries of ../shared/data, 'demo' for the demo library")
    parser.add_argument("--quick-downstream", action="store_true",
                        help="the downstream check with one setting (alpha 1, k_b 1e-2) instead of the grid")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    names = [n for n in args.libraries.split(",") if n]
    libraries = [DATA / n for n in names if n != "demo" and (DATA / n).is_dir()] + ([None] if "demo" in names else [])
    result = _previous(out / "repairs.json", args.quick_downstream)
    check = QUICK_DOWNSTREAM if args.quick_downstream else CHECK_REPAIRS
    for lib in libraries:
        name = lib.name if lib else "demo"
        elastic = run_library(lib, args.cores, out, [check, ELASTIC_FINISH])
        seed_second_run(name, SUFFIX)
        positional = run_library(lib, args.cores, out, [check, *POSITIONAL_FINISH], SUFFIX)
        rows = method_rows(elastic, positional)
        rows["finish_seconds"] = finish_seconds(name, [e["pose"] for e in elastic])
        rows["upstream_seconds"] = {e["pose"]: repair_seconds(e) - (e["seconds_stages"].get("verify") or 0.0)
                                    for e in elastic}
        rows["commit"] = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                                        text=True).stdout.strip()
        rows["library_seconds"] = {stage: benchmark_seconds(ROOT / "results" / name / "benchmarks", stage) or 0.0
                                   for stage in LIBRARY_STAGES.values()}
        result["libraries"][name] = rows
        result["seconds"] = time.perf_counter() - start
        (out / "repairs.md").write_text("\n".join(markdown(result) + finish_markdown(result)))
        (out / "repairs.json").write_text(json.dumps(result, indent=1))
        print(f"wrote {out / 'repairs.md'} ({', '.join(result['libraries'])})", flush=True)


if __name__ == "__main__":
    main()
