"""Benchmark: posefix's exact self-intersection detector against pymeshlab on the same key frames.

For every key frame of every pose of a library (read from ``results/<library>/<pose>/keyframes.h5``),
times ``posefix.mesh.intersections.self_intersecting_pairs`` and pymeshlab's
``compute_selection_by_self_intersections_per_face`` (mesh construction included, best of
``--repeat`` runs each, one thread), and compares the flagged face counts. pymeshlab also flags
some faces whose only intersection is with a face sharing a vertex, which posefix does not count.

    python benchmarks/detector.py --results results/lion-poses --out reports/bench/detector-lion-poses
"""

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np
import pymeshlab
from threadpoolctl import threadpool_limits

from posefix.io.keyframes import read_keyframes
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs


def best_of(fn, repeat):
    """Smallest wall time of ``repeat`` calls, and the last result."""
    best, out = np.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - start)
    return best, out


def pymeshlab_faces(V, F):
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F))
    ms.compute_selection_by_self_intersections_per_face()
    return int(ms.current_mesh().selected_face_number())


def bench_library(results, repeat):
    """One row per pose: frames, faces, seconds of both detectors, face counts."""
    rows = []
    for path in sorted(Path(results).glob("*/keyframes.h5")):
        kf, _ = read_keyframes(path, ["frames", "faces"])
        frames, F = kf["frames"], kf["faces"]
        ours_s = pml_s = 0.0
        ours_n, pml_n = [], []
        for V in frames:
            s, pairs = best_of(lambda: self_intersecting_pairs(V, F), repeat)
            ours_s += s
            ours_n.append(int(intersecting_faces(pairs, len(F)).sum()))
            s, n = best_of(lambda: pymeshlab_faces(V, F), repeat)
            pml_s += s
            pml_n.append(n)
        rows.append({"pose": path.parent.name, "frames": len(frames), "faces": len(F),
                     "posefix_seconds": ours_s, "pymeshlab_seconds": pml_s,
                     "posefix_faces": ours_n, "pymeshlab_faces": pml_n})
        print(f"{path.parent.name}: posefix {ours_s:.3f} s, pymeshlab {pml_s:.3f} s", flush=True)
    return rows


def markdown(library, rows):
    lines = [f"### Detector: {library}", "",
             "| pose | frames | faces | posefix s | pymeshlab s | ratio | faces flagged (posefix / pymeshlab), max over frames |",
             "|---|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        lines.append(f"| {r['pose']} | {r['frames']} | {r['faces']} | {r['posefix_seconds']:.3f} | "
                     f"{r['pymeshlab_seconds']:.3f} | {r['posefix_seconds'] / r['pymeshlab_seconds']:.2f} | "
                     f"{max(r['posefix_faces'])} / {max(r['pymeshlab_faces'])} |")
    ours = sum(r["posefix_seconds"] for r in rows)
    pml = sum(r["pymeshlab_seconds"] for r in rows)
    frames = sum(r["frames"] for r in rows)
    lines += [f"| **all** | {frames} | | {ours:.3f} | {pml:.3f} | {ours / pml:.2f} | |", "",
              f"Per frame: posefix {1000 * ours / frames:.1f} ms, pymeshlab {1000 * pml / frames:.1f} ms "
              f"(ratio = posefix / pymeshlab time; best of repeats, 1 thread, {platform.processor() or platform.machine()})."]
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--results", required=True, help="results/<library> folder with keyframes.h5 per pose")
    parser.add_argument("--out", required=True, help="output path without extension (.json and .md are written)")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    with threadpool_limits(1):
        rows = bench_library(args.results, args.repeat)
    library = Path(args.results).name
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps({"library": library, "rows": rows}, indent=1))
    out.with_suffix(".md").write_text(markdown(library, rows))
    print(markdown(library, rows))


if __name__ == "__main__":
    main()
