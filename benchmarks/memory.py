"""Peak memory and disk per stage, from 5k to 240k vertices (`.venv/bin/python benchmarks/memory.py`):
reports/bench/memory.md.

One pose of each case end to end with ``snakemake --cores N`` (the default one downstream setting): lion-01
(5.0k vertices) and kids-0001's 0001.isometry.1 (59.7k, ``0001.null.0.off.gz`` as reference) with every repair,
and that kids pose and its reference subdivided at the edge midpoints (238.8k vertices, written to
``results/bench-inputs/kids240``) with S0 alone. Per stage: wall seconds and peak memory (Snakemake's benchmark
files, max_rss) next to the ``mem_mb`` its rule asks for (``posefix.workflow.resources.stage_memory_mb``); per
artifact: MB on disk after the run. Snakemake reuses results that are up to date: delete ``results/<case>`` for
fresh figures.
"""

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import trimesh
import yaml

from posefix.io.artifacts import read_artifact
from posefix.io.library import read_pose, read_reference
from posefix.io.meshes import write_mesh
from posefix.workflow.memory import stage_memory_mb
from posefix.workflow.timings import benchmark_row

from notes import with_notes  # benchmarks/notes.py beside: the hand-written prose of benchmarks/notes.md

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSEFIX_DATA", ROOT.parent / "shared" / "data"))
KIDS = ("0001.null.0.off.gz", "0001.isometry.1.off.gz")
CASES = {  # name -> (library folder, reference, pose, repairs)
    "lion-poses": (DATA / "lion-poses", "lion-reference.obj", "lion-01", None),
    "kids-0001": (DATA / "kids-0001", KIDS[0], "0001.isometry.1", None),
    "kids240": (ROOT / "results" / "bench-inputs" / "kids240", "kids240-reference.ply", "kids240-01", "[]"),
}
ORDER = ("validate_reference", "validate", "keyframes", "classify", "constraints", "fit", "integrate", "verify",
         "export", "downstream", "skeleton", "repair_medial", "export_medial", "tet_mesh", "repair_volumetric",
         "export_volumetric", "repair_contact", "export_contact", "render")


def subdivided_kids(folder):
    """kids-0001's reference and pose 0001.isometry.1 with every edge split at its midpoint (the same faces, so the
    same new vertices in the same order), as PLY files in ``folder``."""
    V_ref, F = read_reference(DATA / "kids-0001" / KIDS[0])
    V_pose = read_pose(DATA / "kids-0001" / KIDS[1], V_ref, F)
    folder.mkdir(parents=True, exist_ok=True)
    for name, V in (("kids240-reference", V_ref), ("kids240-01", V_pose)):
        if not (folder / f"{name}.ply").exists():
            write_mesh(folder / f"{name}.ply", *trimesh.remesh.subdivide(V, F))


def run_case(name, cores, root, run=True, extra=()):
    """Run one pose of case ``name`` in the folder ``root`` (unless ``run`` is False: its results are there);
    its stages' seconds and peak MB, the rules' mem_mb, and MB per artifact. ``extra``: more --config entries."""
    folder, reference, pose, repairs = CASES[name]
    start = time.perf_counter()
    if run:
        if name == "kids240":
            subdivided_kids(folder)
        cmd = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--cores", str(cores), "--config",
               f"library={folder}", f"reference={reference}", f"poses={pose}"]
        cmd += ([f"repairs={repairs}"] if repairs else []) + list(extra)
        print("+", " ".join(cmd), flush=True)
        subprocess.run(cmd, cwd=root, check=True)
    results = root / "results" / folder.name
    vertices = int(read_artifact(results / "reference.h5", "validate", [])[1]["metrics"]["vertices"])
    stages = _stages(results, pose)
    return {"case": name, "pose": pose, "vertices": vertices, "wall_seconds": time.perf_counter() - start,
            "stages": stages, "disk_mb": _disk(results, pose) if "render" in stages else {}}


def _stages(results, pose):
    """{stage: {seconds, peak_mb}} from the benchmark files of the library and of ``pose``."""
    out = {}
    for path in sorted((results / "benchmarks").glob("*.tsv")) + sorted((results / "benchmarks" / pose).glob("*.tsv")):
        stage = path.name.split(".")[0]
        row = benchmark_row(path.parent, path.name[:-len(".tsv")])
        out[stage] = {"seconds": float(row["s"]), "peak_mb": float(row["max_rss"])}
    return out


def rule_memory_mb(stage, vertices):
    """The mem_mb the rule of ``stage`` asks for (no run limit): the fit's is its kernel cache's budget (config
    fit.memory_gb) and 2 GB, the others' their stage's measured line (int)."""
    rule = "export_repair" if stage.startswith("export_") else stage
    if rule == "fit":
        return int(1000 * yaml.safe_load((ROOT / "config.yaml").read_text())["fit"]["memory_gb"]) + 2000
    return stage_memory_mb(rule, vertices)


def _disk(results, pose):
    """MB on disk per artifact of ``pose`` (``<pose>/*.h5``, the repaired meshes) and of the library."""
    files = sorted((results / pose).glob("*")) + sorted(results.glob(f"repaired*/{pose}.*"))
    files += sorted(results.glob("*.h5"))
    return {str(f.relative_to(results)): f.stat().st_size / 1e6 for f in files if f.is_file()}


def markdown(cases, cores):
    """The page reports/bench/memory.md (list of str)."""
    lines = ["## Memory and disk per stage", "", __doc__.split("\n\n")[1].replace("\n", " "), "",
             f"`snakemake --cores {cores}`; seconds, peak MB (max_rss) and the rule's mem_mb:", ""]
    found = {s for c in cases for s in c["stages"]}
    stages = [s for s in ORDER if s in found] + sorted(found - set(ORDER))
    lines += ["| stage | " + " | ".join(f"{c['case']} ({c['vertices']:,} vertices): s / peak MB / mem_mb"
                                         for c in cases) + " |", "|---|" + "---:|" * len(cases)]
    for stage in stages:
        cells = [f"{c['stages'][stage]['seconds']:.0f} / {c['stages'][stage]['peak_mb']:.0f} / "
                 f"{rule_memory_mb(stage, c['vertices'])}" if stage in c["stages"] else "-"
                 for c in cases]
        lines.append(f"| {stage} | " + " | ".join(cells) + " |")
    unfinished = [c["case"] for c in cases if not c["disk_mb"]]
    lines += ["", f"Collected before {', '.join(unfinished)} had finished: '-' marks a stage that had not." if unfinished
              else "", "Largest peak: " + ", ".join(
        f"{c['case']} {max(s['peak_mb'] for s in c['stages'].values()) / 1000:.2f} GB in "
        f"{max(c['stages'], key=lambda k: c['stages'][k]['peak_mb'])}" for c in cases) + ".", "",
        "MB on disk after the run, per artifact of the pose and of the library (once for all its poses):", ""]
    for c in filter(lambda c: c["disk_mb"], cases):
        per_pose = sum(mb for name, mb in c["disk_mb"].items() if "/" in name)
        lines += [f"- {c['case']} {c['pose']}: {per_pose:.1f} MB per pose (" + ", ".join(
            f"{name} {mb:.2f}" for name, mb in c["disk_mb"].items()) + ")"]
    return lines + [""]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases", default=",".join(CASES), help="comma-separated cases of: " + ", ".join(CASES))
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--root", default=str(ROOT), help="folder the runs work in (results/, reports/)")
    parser.add_argument("--no-run", action="store_true", help="collect the figures of earlier runs in --root")
    parser.add_argument("--config", nargs="*", default=[], help="more --config entries for the runs")
    parser.add_argument("--merge", default="", help="comma-separated memory.json files of earlier runs to add")
    parser.add_argument("--out", default=str(ROOT / "reports" / "bench"))
    args = parser.parse_args()
    cases = [case for path in filter(None, args.merge.split(",")) for case in json.loads(Path(path).read_text())]
    cases += [run_case(name, args.cores, Path(args.root), not args.no_run, args.config) for name in args.cases.split(",") if name
              and (DATA / "kids-0001" if name == "kids240" else CASES[name][0]).is_dir()]
    cases.sort(key=lambda c: c["vertices"])
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "memory.md").write_text(with_notes("\n".join(markdown(cases, args.cores)), "memory.md"))
    (out / "memory.json").write_text(json.dumps(cases, indent=1))
    print(f"wrote {out / 'memory.md'}")


if __name__ == "__main__":
    main()
