"""S4 benchmark (`make bench`, or alone: `.venv/bin/python benchmarks/volumetric.py`): reports/bench/volumetric.md.

Next to S4 Table 3.1: procedural tet meshes at about the paper's sizes (two bars, a bumpy plane, a cylinder),
the factorization of the reduced Laplacian (S4: 0.039-0.565 s) and S4 iterations per second (one iteration:
linear solve, rotation extraction, differential-coordinate update; S4 ran one per frame), for an edit of each
model: the bars and the cylinder bent by a turned end (rotation interpolation on), the plane translated.
Also S4's high-resolution transfer (§2.4) next to the table's columns "trans" and "recons": seconds to build
the transfer matrix and to carry one frame, for the camel and kids references of ../shared/data (22k and 60k
vertices) and kids subdivided once (239k), each on its tet mesh of the default 2500 surface vertices.
"""

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from posefix.mesh.geometry import bbox_diagonal
from posefix.mesh.rotations import rotation_exp
from posefix.io.library import read_reference
from posefix.volumetric.editor import ROTATIONS, VolumetricEditor
from posefix.volumetric.shapes import tet_cylinder, tet_grid
from posefix.volumetric.tet_mesh import tet_mesh
from posefix.volumetric.transfer import transfer_matrix

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSEFIX_DATA", ROOT.parent / "shared" / "data"))
S4_TRANSFER = {  # Table 3.1: input vertices, tet vertices, transfer precomputation s, seconds per frame
    "Man": (39771, 3474, 42.8, 0.179), "Dragon": (100004, 3021, 94.5, 0.442),
    "Raptor": (175100, 2512, 167.6, 0.965), "Armadillo": (195948, 1688, 96.0, 0.484),
}
TRANSFER_MESHES = {"camel": "camel-poses/camel-reference.obj.gz", "kids": "kids-0001/0001.null.0.off.gz"}
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


def subdivided(V, F):
    """One midpoint subdivision (every triangle into four): (V', F')."""
    edges = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    unique, inverse = np.unique(edges, axis=0, return_inverse=True)
    mid = len(V) + inverse.reshape(3, -1).T  # midpoints of edges 01, 12, 20 of every face
    V2 = np.vstack([V, V[unique].mean(axis=1)])
    F2 = np.concatenate([np.column_stack([F[:, 0], mid[:, 0], mid[:, 2]]), np.column_stack([F[:, 1], mid[:, 1], mid[:, 0]]),
                         np.column_stack([F[:, 2], mid[:, 2], mid[:, 1]]), mid])
    return V2, F2


def transfer_rows(frames=20):
    """Transfer precompute and per-frame seconds on the shared references (missing ones skipped)."""
    rows = {}
    for name, path in TRANSFER_MESHES.items():
        if not (DATA / path).exists():
            continue
        V, F = read_reference(DATA / path)
        meshes = {name: (V, F)}
        if name == "kids":
            meshes["kids subdivided"] = subdivided(V, F)
        for label, (Vm, Fm) in meshes.items():
            X, T = tet_mesh(V, F)  # the coarse tets of the original surface carry the fine one
            start = time.perf_counter()
            B = transfer_matrix(X, T, Vm, 0.05 * bbox_diagonal(Vm))
            precompute = time.perf_counter() - start
            start = time.perf_counter()
            for _ in range(frames):
                B @ X
            rows[label] = {"vertices": len(Vm), "tet_vertices": len(X), "precompute_seconds": precompute,
                           "seconds_per_frame": (time.perf_counter() - start) / frames, "nonzeros_per_row": B.nnz / len(Vm),
                           "rest_error": float(np.abs(B @ X - Vm).max() / bbox_diagonal(Vm))}
    return rows


def transfer_markdown(rows):
    lines = ["", "### S4's high-resolution transfer next to S4 Table 3.1 (\"trans\", \"recons\")", "",
             "Seconds to build the transfer matrix B (Wendland-weighted barycentric coordinates of the tets with a "
             "boundary face within 5 % of the bbox diagonal) and to carry one frame (B X). The issue's bar at 60k "
             "vertices: <= 5 s and <= 0.05 s per frame.", "",
             "| model | vertices | tet vertices | precompute s | s / frame | B nonzeros / row | rest error / d |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for name, (v, k, trans, recons) in S4_TRANSFER.items():
        lines.append(f"| S4 {name} | {v} | {k} | {trans} | {recons} | | |")
    for name, r in rows.items():
        lines.append(f"| {name} | {r['vertices']} | {r['tet_vertices']} | {r['precompute_seconds']:.2f} | "
                     f"{r['seconds_per_frame']:.3f} | {r['nonzeros_per_row']:.0f} | {r['rest_error']:.0e} |")
    return lines + [""]


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
        transfer = transfer_rows()
    (out / "volumetric.md").write_text("\n".join(markdown(rows, args.threads) + transfer_markdown(transfer)))
    (out / "volumetric.json").write_text(json.dumps({"editing": rows, "transfer": transfer}, indent=1))
    print(f"wrote {out / 'volumetric.md'}")


if __name__ == "__main__":
    main()
