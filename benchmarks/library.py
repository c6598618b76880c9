"""A 59-pose library end to end (`make bench`, or alone: `.venv/bin/python benchmarks/library.py`):
reports/bench/library.md.

horse-poses' 10 poses and horse-gallop's 49 frames (one horse mesh: the same connectivity) as one library,
``horse-reference.obj`` its reference, with every repair and the default downstream setting, ``snakemake --cores N``
as a user runs it (``keep_intermediates`` off). Per stage, from Snakemake's benchmark files: wall seconds and CPU
seconds over all poses and per pose, the largest peak memory (max_rss), and the disk its files take after the run;
the stages that run once per library (the reference's validation, the medial repair's skeleton, the volumetric
repair's tet mesh) apart from the per-pose ones. Snakemake reuses results that are up to date: delete
``results/horse-59`` for fresh figures.
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import h5py

from posefix.report.tables import entry_status
from posefix.workflow.timings import benchmark_row

from memory import ORDER  # benchmarks/memory.py beside: the stages in pipeline order
from notes import with_notes  # benchmarks/notes.py beside: the hand-written prose of benchmarks/notes.md

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSEFIX_DATA", ROOT.parent / "shared" / "data"))
NAME = "horse-59"
REFERENCE = "horse-reference.obj"
SOURCES = ("horse-poses", "horse-gallop")


def library_folder(root):
    """``results/bench-inputs/horse-59`` under ``root``: links to the horse reference, its 10 poses and the 49 gallop
    frames (Path); None when the data are absent."""
    files = [f for name in SOURCES if (DATA / name).is_dir() for f in sorted((DATA / name).iterdir())
             if f.name.endswith((".obj", ".obj.gz"))]
    if len(files) < 60:
        return None
    folder = root / "results" / "bench-inputs" / NAME
    folder.mkdir(parents=True, exist_ok=True)
    for f in files:
        if not (folder / f.name).exists():
            (folder / f.name).symlink_to(f)
    return folder


def run_library(folder, root, cores, extra=()):
    """Run the pipeline on the library ``folder`` in ``root`` (``extra``: more --config entries); the run's wall and
    CPU seconds (its processes')."""
    cmd = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--cores", str(cores), "--config",
           f"library={folder}", f"reference={REFERENCE}", *extra]
    print("+", " ".join(cmd), flush=True)
    start, cpu = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, cwd=root, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.perf_counter() - start, (after.ru_utime + after.ru_stime) - (cpu.ru_utime + cpu.ru_stime)


def stage_rows(results):
    """{stage: {runs, seconds, cpu_seconds, peak_mb, once}} over the library's benchmark files (``once``: a stage run
    once per library); ``export_*.<ext>`` counted as ``export_*``."""
    rows = {}
    for path in sorted((results / "benchmarks").rglob("*.tsv")):
        stage = path.name.split(".")[0]
        row = benchmark_row(path.parent, path.name[:-len(".tsv")])
        entry = rows.setdefault(stage, {"runs": 0, "seconds": 0.0, "cpu_seconds": 0.0, "peak_mb": 0.0,
                                        "once": path.parent == results / "benchmarks"})
        entry["runs"] += 1
        entry["seconds"] += float(row["s"])
        entry["cpu_seconds"] += float(row["cpu_time"])
        entry["peak_mb"] = max(entry["peak_mb"], float(row["max_rss"]))
    return rows


def disk_mb(results, poses):
    """MB on disk after the run: ``{"poses": {kind: MB}, "library": {file: MB}}``, the kinds ``<name>`` of
    ``<pose>/<name>`` and ``repaired*/`` summed over ``poses``, the library's own files (``*.h5``) once."""
    per_pose = {}
    for pose in poses:
        for f in list((results / pose).glob("*")) + list(results.glob(f"repaired*/{pose}.*")):
            key = f.name if f.parent.name == pose else f.parent.name + "/"
            per_pose[key] = per_pose.get(key, 0.0) + f.stat().st_size / 1e6
    library = {f.name: f.stat().st_size / 1e6 for f in sorted(results.glob("*.h5"))}
    return {"poses": dict(sorted(per_pose.items())), "library": library}


def contact_setup_seconds(results, poses):
    """Seconds the contact repair spent setting the contact solver up on the reference, summed over ``poses`` (its
    artifact's ``prepare`` timing; verify builds the same solver once per pose too)."""
    total = 0.0
    for pose in poses:
        with h5py.File(results / pose / "contact.h5", "r") as fh:
            total += float(fh["timings"].attrs["prepare"])
    return total


def markdown(result):
    """The page reports/bench/library.md (list of str)."""
    poses, rows = result["poses"], result["stages"]
    stages = [s for s in ORDER if s in rows] + sorted(set(rows) - set(ORDER))
    per_pose = [s for s in stages if not rows[s]["once"]]
    lines = ["## A 59-pose library end to end", "", __doc__.split("\n\n")[1].replace("\n", " ").replace("``", "`"), "",
             f"`snakemake --cores {result['cores']}`: {poses} poses in {result['wall_seconds'] / 60:.1f} min wall "
             f"({result['wall_seconds'] / poses:.1f} s per pose), {result['cpu_seconds'] / 60:.1f} min CPU "
             f"({result['cpu_seconds'] / poses:.1f} s per pose); statuses: " +
             ", ".join(f"{n} {kind}" for kind, n in sorted(result["statuses"].items())) + ".", "",
             "| stage | runs | wall s | wall s per pose | CPU s | peak MB |", "|---|---:|---:|---:|---:|---:|"]
    for stage in [s for s in stages if rows[s]["once"]] + per_pose:
        r = rows[stage]
        share = "once" if r["once"] else f"{r['seconds'] / poses:.1f}"
        lines.append(f"| {stage} | {r['runs']} | {r['seconds']:.0f} | {share} | {r['cpu_seconds']:.0f} | "
                     f"{r['peak_mb']:.0f} |")
    total, disk = sum(rows[s]["seconds"] for s in per_pose), result["disk_mb"]
    pose_mb = sum(disk["poses"].values())
    stage_cpu = sum(r["cpu_seconds"] for r in rows.values())
    lines += ["", f"Per-pose stages: {total:.0f} s of stage wall time in all, {total / poses:.1f} s per pose; the "
              f"once-per-library stages: {sum(rows[s]['seconds'] for s in stages if rows[s]['once']):.0f} s. The "
              f"contact solver's set-up on the reference is per pose, in verify and repair_contact alike: "
              f"{result['contact_setup_seconds']:.1f} s over the poses in repair_contact. The stages' benchmark files "
              f"count {stage_cpu / 60:.1f} min of CPU; the rest of the run's, "
              f"{(result['cpu_seconds'] - stage_cpu) / 60:.1f} min, is Snakemake's own process (scheduling, file "
              "checks, benchmark sampling) and what the sampling misses of short jobs.", "",
              f"Disk after the run: {pose_mb:.1f} MB for the poses, {pose_mb / poses:.2f} MB per pose (" +
              ", ".join(f"{name} {mb:.1f}" for name, mb in disk["poses"].items()) + " MB), and once for the "
              "library " + ", ".join(f"{name} {mb:.1f}" for name, mb in disk["library"].items()) + " MB.", ""]
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--root", default=str(ROOT), help="folder the run works in (results/, reports/)")
    parser.add_argument("--config", nargs="*", default=[],
                        help="more --config entries for the run (poses=horse-01,horse-gallop-01: a quick look)")
    parser.add_argument("--out", default=str(ROOT / "reports" / "bench"))
    args = parser.parse_args()
    root = Path(args.root)
    folder = library_folder(root)
    if folder is None:
        print(f"{DATA}: horse-poses and horse-gallop are absent; no library benchmark")
        return
    wall, cpu = run_library(folder, root, args.cores, args.config)
    summary = json.loads((root / "reports" / NAME / "summary.json").read_text())["poses"]
    statuses = {}
    for entry in summary:
        kind = entry_status(entry)[0]
        statuses[kind] = statuses.get(kind, 0) + 1
    results, poses = root / "results" / NAME, [entry["pose"] for entry in summary]
    result = {"cores": args.cores, "poses": len(summary), "wall_seconds": wall, "cpu_seconds": cpu,
              "statuses": statuses, "stages": stage_rows(results), "disk_mb": disk_mb(results, poses),
              "contact_setup_seconds": contact_setup_seconds(results, poses)}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "library.md").write_text(with_notes("\n".join(markdown(result)), "library.md"))
    (out / "library.json").write_text(json.dumps(result, indent=1))
    print(f"wrote {out / 'library.md'}")


if __name__ == "__main__":
    main()
