"""Benchmark: ipctk's broad phases on the contact solver's two queries, to choose the one it uses.

For one pose of lion, cat and kids-0001 (../shared/data), on a collision mesh of the reference, the broad phases
ipctk offers (the brute force below 20k vertices) each find the candidate pairs of

- a swept step: the reference moved toward the target by one mean edge length at most (the substep of
  ``ContactSolver.collision_free_step``), boxes inflated by 1e-4 d;
- the static set at the largest activation distance: boxes inflated by ``contact.dhat`` / 2 (1e-3 d / 2 by
  default, ``ContactSolver.candidates``).

Best of 3 builds each, one thread. ``Candidates.build`` without a broad phase uses ipctk's default, which the
contact solver does: the table says which one that is and how it compares.

    python benchmarks/broad_phase.py --out reports/bench
"""

import argparse
import json
import time
from pathlib import Path

import ipctk
import numpy as np
from threadpoolctl import threadpool_limits

from posefix.io.library import read_pose_pair

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
CASES = {"lion-poses": ("lion-reference.obj", "lion-04.obj"), "cat-poses": ("cat-reference.obj", "cat-04.obj"),
         "kids-0001": ("0001.null.0.off.gz", "0001.isometry.1.off.gz")}
METHODS = ("BruteForce", "HashGrid", "SpatialHash", "SweepAndPrune", "BVH", "LBVH")
BRUTE_FORCE_VERTICES = 20000  # above, the brute force takes minutes per build


def best_of(build, repeat=3):
    """Smallest wall seconds of ``repeat`` calls of ``build`` (returns the candidates), and the candidate count."""
    best, count = np.inf, 0
    for _ in range(repeat):
        start = time.perf_counter()
        count = len(build())
        best = min(best, time.perf_counter() - start)
    return best, count


def queries(V, target, F):
    """The collision mesh and the two queries: {name: (vertices at t0[, at t1], inflation)}."""
    E = ipctk.edges(F)
    d = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    edge = float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).mean())
    move = target - V
    step = V + move * min(1.0, edge / max(float(np.linalg.norm(move, axis=1).max()), 1e-300))
    return ipctk.CollisionMesh(V, E, F), {"swept step": (V, step, 1e-4 * d), "static at dhat": (V, 0.5e-3 * d)}


def bench_case(name, files):
    """Rows of one case: per query and broad phase, seconds and candidates."""
    V, target, F = read_pose_pair(*(DATA / name / f for f in files))[:3]
    mesh, cases = queries(V, target, F)
    rows = []
    for query, args in cases.items():
        default = ipctk.Candidates()
        seconds, count = best_of(lambda: default.build(mesh, *args) or default)
        rows.append({"case": name, "vertices": len(V), "query": query, "method": "default", "seconds": seconds,
                     "candidates": count})
        for method in METHODS:
            if not hasattr(ipctk, method) or (method == "BruteForce" and len(V) > BRUTE_FORCE_VERTICES):
                continue
            c, broad = ipctk.Candidates(), getattr(ipctk, method)()
            seconds, count = best_of(lambda: c.build(mesh, *args, broad_phase=broad) or c)
            rows.append({"case": name, "vertices": len(V), "query": query, "method": method, "seconds": seconds,
                         "candidates": count})
    return rows


def markdown(rows):
    """The page: per case and query, each broad phase's milliseconds and candidates, and its time over the
    default's."""
    lines = ["## Broad phase of the contact solver", "",
             "ipctk's broad phases on the contact solver's queries (`benchmarks/broad_phase.py`, one thread, best of "
             "3): a swept step of one edge length from the reference toward the target, and the static pairs within "
             "`contact.dhat`. \"default\" is `Candidates.build` without a broad phase, which the solver calls.", "",
             "| case | vertices | query | broad phase | ms | candidates | ms / default's |",
             "|---|---:|---|---|---:|---:|---:|"]
    default = {(r["case"], r["query"]): r["seconds"] for r in rows if r["method"] == "default"}
    for r in rows:
        lines.append(f"| {r['case']} | {r['vertices']} | {r['query']} | {r['method']} | {1e3 * r['seconds']:.1f} | "
                     f"{r['candidates']} | {r['seconds'] / default[r['case'], r['query']]:.2f} |")
    return "\n".join(lines + ["", fastest(rows)]) + "\n"


def fastest(rows):
    """One sentence: the broad phase fastest on each query (the default aside), and how much slower the others are."""
    named = [r for r in rows if r["method"] != "default"]
    best = {}
    for r in named:
        key = (r["case"], r["query"])
        best[key] = min(best.get(key, r), r, key=lambda x: x["seconds"])
    winners = sorted({r["method"] for r in best.values()})
    others = [r["seconds"] / best[r["case"], r["query"]]["seconds"] for r in named
              if r is not best[r["case"], r["query"]] and r["method"] != "BruteForce"]
    return (f"Fastest on each query: {', '.join(winners)}; the other broad phases (the brute force aside) take "
            f"{min(others):.1f}-{max(others):.1f}x its time.")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default=str(ROOT / "reports" / "bench"))
    args = parser.parse_args()
    threadpool_limits(1)
    ipctk.set_num_threads(1)  # as ContactSolver with its stage's threads (1)
    rows = [row for name, files in CASES.items() if (DATA / name).is_dir() for row in bench_case(name, files)]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "broad-phase.md").write_text(markdown(rows))
    (out / "broad-phase.json").write_text(json.dumps({"ipctk": ipctk.__version__, "rows": rows}, indent=1))
    print(f"wrote {out / 'broad-phase.md'}")


if __name__ == "__main__":
    main()
