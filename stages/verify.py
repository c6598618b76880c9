"""Stage verify: check the repaired pose, fall back to the target where needed, write the mesh.

Counts intersecting faces of reference, target and repaired pose ("new": intersecting in the
repaired pose, not in the reference), measures the deviation from the target over V_C and the rest,
replaces regions by the target where integration could not reach it (S0 Fig. 9) or where new
intersections appear that the target does not have (see ``posefix.verification``), and writes the
repaired pose in the target's own file format with identical faces and vertex order.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "lib"))

import json  # noqa: E402

import posefix  # noqa: E402,F401  (runtime defaults before numpy)
import numpy as np  # noqa: E402

from posefix.cli import Timings, run_stage, stage_parser  # noqa: E402
from posefix.h5io import read_artifact, write_artifact  # noqa: E402
from posefix.intersections import intersecting_faces, self_intersecting_pairs  # noqa: E402
from posefix.io import InputError, read_mesh, write_like  # noqa: E402
from posefix.verification import REPLACED_FAR, REPLACED_NEW_INTERSECTION, deviation, fallback  # noqa: E402

DOCS = {
    "repaired": ("length", "repaired vertex positions (after the fallback), (n, 3) float64"),
    "deviation": ("1", "|repaired - target| / bbox diagonal per vertex, (n,) float64"),
    "replaced": ("flags", "fallback per vertex: 1 far from target (global intersection), 2 new intersection, (n,) uint8"),
    "new_faces": ("bool", "faces intersecting in the repaired pose but not in the reference, (m,) bool"),
    "pairs": ("index", "intersecting face pairs (f < g) of the repaired pose, (P, 2) int64"),
}


def build_parser():
    parser = stage_parser("verify", __doc__)
    parser.add_argument("--keyframes", required=True, help="keyframes.h5 of the pose (reference, target, faces)")
    parser.add_argument("--classify", required=True, help="classify.h5 of the pose (V_C, reference intersections)")
    parser.add_argument("--integrate", required=True, help="integrate.h5 of the pose")
    parser.add_argument("--fit", required=True, help="fit.h5 of the pose (eps)")
    parser.add_argument("--target", required=True, help="the target mesh file (its format is reproduced)")
    parser.add_argument("--mesh", required=True, help="repaired mesh file to write (same format as --target)")
    parser.add_argument("--out", required=True, help="verify.h5 to write")
    parser.add_argument("--fallback-eps", type=float, default=100.0,
                        help="a constrained vertex farther than this many eps from its target triggers the fallback")
    parser.add_argument("--ring", type=int, default=1, help="rings grown around fallback triggers")
    parser.add_argument("--no-repair-new", dest="repair_new", action="store_false",
                        help="do not replace regions with new intersections by the target")
    return parser


def main(args, log):
    timings = Timings()
    with timings.step("read", log):
        kf, _ = read_artifact(args.keyframes, "keyframes", ["reference", "target", "faces"])
        cl, _ = read_artifact(args.classify, "classify", ["mask", "pairs", "pair_offsets"])
        it, _ = read_artifact(args.integrate, "integrate", ["positions"])
        _, fattrs = read_artifact(args.fit, "fit", [])
        V_file, F_file = read_mesh(args.target)
    V_ref, V_tgt, F = kf["reference"], kf["target"], kf["faces"]
    if not (np.array_equal(F_file, F) and np.array_equal(V_file, V_tgt)):
        raise InputError(args.target, "is not the target these artifacts were computed from")
    d = float(fattrs["metrics"]["bbox_diagonal"])
    eps = json.loads(fattrs["config"])["eps_rel"] * d
    m, mask = len(F), cl["mask"]
    offsets, pairs = cl["pair_offsets"], cl["pairs"]
    reference_faces = intersecting_faces(pairs[offsets[0]:offsets[1]], m)
    target_faces = intersecting_faces(pairs[offsets[-2]:offsets[-1]], m)
    keyframes_max = max(intersecting_faces(pairs[offsets[k]:offsets[k + 1]], m).sum() for k in range(len(offsets) - 1))
    with timings.step("fallback", log):
        X, replaced, new = fallback(it["positions"], V_tgt, F, mask, reference_faces, args.fallback_eps * eps,
                                    args.ring, args.repair_new, log)
    with timings.step("verify", log):
        repaired_pairs = self_intersecting_pairs(X, F)
        repaired_faces = intersecting_faces(repaired_pairs, m)
        dev, summary = deviation(X, V_tgt, mask, d)
    log.info("intersecting faces: reference %d, target %d, repaired %d (new %d); %d vertices from the target",
             reference_faces.sum(), target_faces.sum(), repaired_faces.sum(), new.sum(), np.count_nonzero(replaced))
    log.info("deviation / d: constrained mean %.2e max %.2e, free mean %.2e max %.2e", summary["constrained_mean"],
             summary["constrained_max"], summary["free_mean"], summary["free_max"])
    with timings.step("write", log):
        write_like(args.mesh, X, F, args.target)
    write_artifact(
        args.out, "verify",
        {"repaired": X, "deviation": dev, "replaced": replaced, "new_faces": new, "pairs": repaired_pairs},
        params={"fallback_eps": args.fallback_eps, "ring": args.ring, "repair_new": args.repair_new},
        inputs=[args.keyframes, args.classify, args.integrate, args.fit, args.target], timings=timings,
        metrics={"vertices": len(X), "faces": m, "intersecting_faces_reference": int(reference_faces.sum()),
                 "intersecting_faces_target": int(target_faces.sum()),
                 "intersecting_faces_repaired": int(repaired_faces.sum()), "repaired_new": int(new.sum()),
                 "intersecting_faces_keyframes_max": int(keyframes_max),
                 "fallback_vertices": int(np.count_nonzero(replaced)),
                 "fallback_far": int(np.count_nonzero(replaced & REPLACED_FAR)),
                 "fallback_new_intersection": int(np.count_nonzero(replaced & REPLACED_NEW_INTERSECTION)),
                 "mesh": str(args.mesh), **{f"deviation_{k}": v for k, v in summary.items()}},
        docs=DOCS)


if __name__ == "__main__":
    run_stage(build_parser(), main)
