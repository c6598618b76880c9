"""USD and glTF pose libraries (`make bench`, or alone: `.venv/bin/python benchmarks/containers.py`):
reports/bench/containers.md.

A synthetic library of production size (50,000 points, 100 poses) in each container (.usdc, .usda, .glb) and, as
the peer, the same poses as a folder of binary PLY and of OBJ files: the file sizes, what a pose costs to read
(stage unpack reads one pose from the file; the folder's stages read one mesh file), what the workflow reads at its
start (every pose's digest, so that only changed poses rerun), and the write-back of every pose (stage pack).
Seconds are the median of three, on this machine.

With ../shared/data present, the lion library (every pose) also runs through the workflow as a folder of OBJ files,
as one USD file (frames), as one GLB file (morph targets) and, where Blender is (the checkout's .venv-blender, or
$POSEFIX_BLENDER), as one Alembic cache (frames), space-time alone with one downstream step: the statuses and
intersecting-face counts of the summaries side by side (the float32 the container files hold may move a count; the
test suite compares the demo limb's containers bit for bit).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from containers import library_into_containers, write_gltf, write_usd_frames  # noqa: E402  (tests/containers.py)
from posefix.io.containers import open_container  # noqa: E402
from posefix.io.meshes import write_mesh  # noqa: E402
from posefix.report.tables import entry_status  # noqa: E402

POINTS, POSES = 50_000, 100
LION = Path(os.environ.get("POSEFIX_DATA", ROOT.parent / "shared" / "data")) / "lion-poses"


def seconds(call, repeat=3):
    """Median wall seconds of ``call()`` over ``repeat`` calls."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def in_fresh_process(code):
    """Wall seconds of ``python -c code`` (the interpreter's start and imports included), median of three."""
    return seconds(lambda: subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT))


def library(folder):
    """The synthetic library: its files by kind ({kind: path}) under ``folder``."""
    rng = np.random.default_rng(0)
    V = rng.random((POINTS, 3))
    F = rng.integers(0, POINTS, (2 * POINTS, 3))
    poses = [V + 1e-3 * k * np.sin(V * k) for k in range(1, POSES + 1)]
    write_mesh(folder / "ply" / "lib-001.ply", poses[0], F)
    write_mesh(folder / "obj" / "lib-001.obj", poses[0], F)
    return {"usdc": write_usd_frames(folder / "lib.usdc", V, poses, F),
            "usda": write_usd_frames(folder / "lib.usda", V, poses, F),
            "glb": write_gltf(folder / "lib.glb", V, poses, F),
            "ply": folder / "ply" / "lib-001.ply", "obj": folder / "obj" / "lib-001.obj"}


def row(kind, path, scratch):
    """One table row of the container or mesh file ``path``."""
    size = path.stat().st_size * (1 if kind in ("usdc", "usda", "glb") else POSES)
    if kind in ("ply", "obj"):
        read = in_fresh_process(f"from posefix.io.meshes import read_mesh; read_mesh({str(path)!r})")
        return f"| folder of {kind.upper()} | {size / 1e6:.0f} | {read:.2f} | – | – |"
    read = in_fresh_process(f"from posefix.io.containers import open_container; "
                            f"b = open_container({str(path)!r}); b.points(list(b.members)[50])")
    digests = in_fresh_process(f"from posefix.io.containers import member_digests; member_digests({str(path)!r})")
    box = open_container(path)
    moved = {name: box.points(name) + 0.01 for name in list(box.members)[1:]}
    write = seconds(lambda: box.write(scratch / path.name, moved))
    return f"| {kind} | {size / 1e6:.0f} | {read:.2f} | {digests:.2f} | {write:.2f} |"


BLENDER_PYTHON = ROOT / ".venv-blender" / "bin" / "python"


def lion_runs(work, cores):
    """The lion library run as a folder and as each container file in ``work``: {kind: [(pose, status, intersecting
    faces)] in pose order}."""
    if BLENDER_PYTHON.is_file():
        os.environ.setdefault("POSEFIX_BLENDER", str(BLENDER_PYTHON))
    files, names = library_into_containers(LION, work, "lion", alembic="POSEFIX_BLENDER" in os.environ)
    runs = {}
    for kind, library in {"folder": LION, **files}.items():
        name = "lion-poses" if kind == "folder" else "lion"
        subprocess.run([sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--directory",
                        str(work / kind), "--cores", str(cores), f"reports/{name}/summary.json", "--config",
                        f"library={library}", "repairs=[]", "downstream={'max_iters': 1}"]
                       + (["reference=1"] if kind == "abc" else []), check=True)
        summary = json.loads((work / kind / "reports" / name / "summary.json").read_text())
        runs[kind] = [(pose, *entry) for pose, entry in zip(names, [
            (entry_status(e)[0], e["intersecting_faces"]) for e in summary["poses"]])]
    return runs


KINDS = {"usdc": ".usdc (frames)", "glb": ".glb (morph targets)", "abc": ".abc (frames, through Blender)"}


def lion_section(runs):
    """The markdown lines comparing :func:`lion_runs`' summaries."""
    def cell(status, faces):
        return f"{status}, {faces['repaired_new']} new, {faces['repaired']} in all"

    kinds = [kind for kind in KINDS if kind in runs]
    rows = [f"| {pose[0]} | " + " | ".join(cell(*runs[kind][k][1:]) for kind in ["folder", *kinds]) + " |"
            for k, pose in enumerate(runs["folder"])]
    same = all(a[1] == b[1] and {k: v for k, v in a[2].items() if k != "repaired"} ==
               {k: v for k, v in b[2].items() if k != "repaired"} for kind in kinds
               for a, b in zip(runs["folder"], runs[kind]))
    return ["### The lion library as a folder and as one file", "",
            "Space-time alone, one downstream step; each pose's status and intersecting faces after the repair "
            "(new ones, and in all: the reference's own 138 it keeps may move with the float32 input).", "",
            "| pose | folder of OBJ | " + " | ".join(KINDS[kind] for kind in kinds) + " |",
            "|---|---|" + "---|" * len(kinds), *rows, "",
            f"Statuses and every count but the total as the folder's: **{'yes' if same else 'no'}**.", ""]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(ROOT / "reports" / "bench"), help="folder of containers.md")
    parser.add_argument("--cores", type=int, default=2, help="cores of the lion runs")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        files = library(Path(tmp))
        (Path(tmp) / "out").mkdir()
        rows = [row(kind, path, Path(tmp) / "out") for kind, path in files.items()]
        lion = lion_section(lion_runs(Path(tmp), args.cores)) if LION.is_dir() else []
    lines = ["## USD and glTF pose libraries", "",
             f"A synthetic library of {POINTS:,} points and {POSES} poses (`benchmarks/containers.py`); seconds are "
             "medians of three on this machine, a fresh interpreter's start and imports included where marked.", "",
             "| library | MB | read one pose, fresh process (s) | digests of all poses, fresh process (s) | "
             "write every pose back (s) |", "|---|---|---|---|---|", *rows, "",
             "Stage unpack reads one pose per job (a .usdc is read lazily, a .usda parsed whole); the workflow reads "
             "every pose's digest once when the file changed (cached in .snakemake/); stage pack writes the file of "
             "each repair once.", "", *lion]
    Path(args.out).mkdir(parents=True, exist_ok=True)
    (Path(args.out) / "containers.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
