"""S4 benchmark (`make bench`, or alone: `.venv/bin/python benchmarks/volumetric.py`): reports/bench/volumetric.md.

Next to S4 Table 3.1: procedural tet meshes at about the paper's sizes (two bars, a bumpy plane, a cylinder),
the factorization of the reduced Laplacian (S4: 0.039-0.565 s) and S4 iterations per second (one iteration:
linear solve, rotation extraction, differential-coordinate update; S4 ran one per frame), for an edit of each
model: the bars and the cylinder bent by a turned end (rotation interpolation on), the plane translated.
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from posefix.mesh.rotations import rotation_exp
from posefix.volumetric.editor import ROTATIONS, VolumetricEditor
from posefix.volumetric.shapes import tet_cylinder, tet_grid

ROOT = Path(__file__).resolve().parents[1]
S4 = {  # Table 3.1: vertices / tets of T, factorization seconds, frames per second (Pentium 4 3 GHz)
    "bar (small)": (857, 2289, 0.039, 120), "bar": (1440, 4302, None, 85),
    "bumpy plane": (5066, 16028, 0.331, 20), "cylinder": (7235, 23831, 0.565, 12),
}


def models():
    """Name -> (X, T, length along x) at about S4's sizes."""
    plane_X, plane_T = tet_grid((50, 50, 1), (10.0, 10.0, 0.2))
    plane_X[:, 2] += 0.3 * np.sin(plane_X[:, 0]) * np.cos(plane_X[:, 1])  # the bumps
    return {"bar (small)": (*tet_grid((53, 3, 3), (10.0, 1.0, 1.0)), 10.0),
            "bar": (*tet_grid((89, 3, 3), (10.0, 1.0, 1.0)), 10.0),
            "bumpy plane": (plane_X, plane_T, 10.0),
            "cylinder": (*tet_cylinder(0.5, 10.0, 147, 3), 10.0)}


def edit_setup(name, X, T, length):
    """Handles, region handles, targets and region rotations of the benchmark edit of a model."""
    centre = X[T].mean(axis=1)[:, 0]
    start, end = np.flatnonzero(centre < 0.2), np.flatnonzero(centre > length - 0.2)
    fixed, moved = np.unique(T[start]), np.unique(T[end])
    if name == "bumpy plane":
        return np.r_[fixed, moved], [], np.r_[X[fixed], X[moved] + [0.0, 0.0, 2.0]], None
    turn = rotation_exp(np.array([[0.0, 0.0, np.pi / 2]]))[0]
    tip = X[moved] - [length, 0.0, 0.0]
    r = length / (np.pi / 2)
    return (np.r_[fixed, moved], [start, end], np.r_[X[fixed], [r, r, 0.0] + tip @ turn.T],
            np.stack([np.eye(3), turn]))


def measure(name, X, T, length, iterations=20):
    handles, regions, targets, rotations = edit_setup(name, X, T, length)
    t0 = time.perf_counter()
    editor = VolumetricEditor(X, T, handles, regions=regions)
    factor_s = time.perf_counter() - t0
    row = {"vertices": len(X), "tets": len(T), "factor_seconds": factor_s}
    for method in ROTATIONS:
        editor.rotation = method
        editor.solve(targets, 1, region_rotations=rotations)  # warm-up
        result = editor.solve(targets, iterations, region_rotations=rotations)
        row[f"{method}_iterations_per_second"] = (iterations + 1) / result.seconds
        row[f"{method}_shear"] = [float(result.shear[0]), float(result.shear[-1])]
    return row


def markdown(rows, threads):
    lines = ["## S4: volumetric editing next to S4 Table 3.1", "",
             f"`benchmarks/volumetric.py`, {threads} threads. One iteration: linear solve, rotation extraction, "
             "differential-coordinate update (S4 ran one per frame); rotations by the polar factor (scaled Newton, "
             "the default) or S4's averaging (Eq. 2.8, three steps). Shear: volume-weighted mean |T_j - R_j| after "
             "the linear solve and after 20 iterations.", "",
             "| model | S4 vertices / tets | ours | S4 factorization s | ours | S4 fps | iterations/s, polar | "
             "ratio | averaging | ratio | shear, polar | averaging |",
             "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---|---|"]
    for name, r in rows.items():
        v, t, f, fps = S4[name]
        polar, average = r["polar_iterations_per_second"], r["average_iterations_per_second"]
        shear = [" -> ".join(f"{x:.3f}" for x in r[f"{m}_shear"]) for m in ROTATIONS]
        lines.append(f"| {name} | {v} / {t} | {r['vertices']} / {r['tets']} | {f if f else 'N/A'} | "
                     f"{r['factor_seconds']:.3f} | {fps} | {polar:.0f} | {polar / fps:.1f} | {average:.0f} | "
                     f"{average / fps:.1f} | {shear[0]} | {shear[1]} |")
    return lines + [""]


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", default=str(ROOT / "reports" / "bench"))
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with threadpool_limits(args.threads):
        rows = {name: measure(name, *model) for name, model in models().items()}
    (out / "volumetric.md").write_text("\n".join(markdown(rows, args.threads)))
    (out / "volumetric.json").write_text(json.dumps(rows, indent=1))
    print(f"wrote {out / 'volumetric.md'}")


if __name__ == "__main__":
    main()
