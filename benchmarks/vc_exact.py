"""V_C exact away from contacts (`make bench` after `benchmarks/repairs.py`, or alone: `.venv/bin/python benchmarks/vc_exact.py`):
reports/bench/vc-exact.md.

For every pose that `benchmarks/repairs.py` repaired with the contact finish (results/<library>): the constrained
vertices (V_C) farther than 2 dhat from every vertex in contact (the contact solver's active pairs at the repaired
pose, closer than dhat, the reference's own pairs excluded) and their largest deviation from the target, against
the bar of issue 27 (1e-6 d); V_C's largest deviation of all (bar 1e-3 d). Lengths relative to the bbox diagonal d.
"""

import argparse
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from posefix.io.artifacts import read_artifact
from posefix.mesh.contact_solver import ContactSolver
from posefix.spacetime.classification import split_frames
from posefix.verify.state import RepairProblem

ROOT = Path(__file__).resolve().parents[1]
LIBRARIES = ("lion-poses", "cat-poses", "horse-poses", "camel-poses", "demo")


def pose_row(folder):
    """(V_C vertices, of them farther than 2 dhat from a contact, their max deviation / d, V_C max / d) of the
    pose whose artifacts are in ``folder``."""
    kf, _ = read_artifact(folder / "keyframes.h5", "keyframes", ["reference", "target", "faces"])
    cl, _ = read_artifact(folder / "classify.h5", "classify", ["mask", "pairs", "pair_offsets"])
    ve, attrs = read_artifact(folder / "verify.h5", "verify", ["repaired"])
    problem = RepairProblem.build(kf["reference"], kf["target"], kf["faces"], cl["mask"],
                                  split_frames(cl["pairs"], cl["pair_offsets"]))
    solver = ContactSolver(problem.V_ref, problem.F, problem.frame_pairs[0])
    X = ve["repaired"]
    contact = solver.contact_vertices(solver.collisions(X), len(X))
    d = solver.d
    away = np.full(len(X), np.inf)
    if contact.any():
        away = cKDTree(X[contact]).query(X)[0]
    far = problem.mask & (away > 2 * solver.dhat)
    deviation = np.linalg.norm(X - problem.V_tgt, axis=1) / d
    return int(problem.mask.sum()), int(far.sum()), float(deviation[far].max(initial=0.0)), \
        float(deviation[problem.mask].max(initial=0.0))


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--results", default=str(ROOT / "results"))
    parser.add_argument("--out", default=str(ROOT / "reports" / "bench"))
    args = parser.parse_args()
    lines = ["### V_C exact away from contacts (contact finish)", "", __doc__.split("\n\n")[1].replace("\n", " "), "",
             "| library | poses | V_C vertices | farther than 2 dhat from a contact | their max deviation | V_C max |",
             "|---|---:|---:|---:|---:|---:|"]
    for name in LIBRARIES:
        poses = sorted(p.parent for p in (Path(args.results) / name).glob("*/verify.h5"))
        rows = np.array([pose_row(p) for p in poses]).reshape(-1, 4)
        if len(rows):
            lines.append(f"| {name} | {len(rows)} | {int(rows[:, 0].sum())} | {int(rows[:, 1].sum())} | "
                         f"{rows[:, 2].max():.1e} | {rows[:, 3].max():.1e} |")
            print(lines[-1], flush=True)
    Path(args.out, "vc-exact.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
