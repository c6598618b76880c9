"""Stage verify: check the repaired pose and fall back to the target where integration could not help.

Counts intersecting faces of reference, target and repaired pose ("new": intersecting in the
repaired pose, not in the reference), replaces regions by the target where integration could not
reach it (S0 Fig. 9), untangles new intersections, puts the untouched constrained vertices exactly
on their targets (blending the fit's residual into the rest), and measures the deviation from the
target over V_C and the rest (see ``posefix.verification``). Stage ``export`` writes the mesh.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "lib"))

import json  # noqa: E402

import posefix  # noqa: E402,F401  (runtime defaults before numpy)
import numpy as np  # noqa: E402

from posefix.classification import split_frames  # noqa: E402
from posefix.cli import Timings, run_stage, stage_parser  # noqa: E402
from posefix.h5io import read_artifact, write_artifact  # noqa: E402
from posefix.intersections import intersecting_faces, self_intersecting_pairs  # noqa: E402
from posefix.topology import vertex_adjacency  # noqa: E402
from posefix.verification import (PUSHED, REPLACED_PASS_THROUGH, REPRODUCED, deviation, fallback,  # noqa: E402
                                  reproduce_targets)

DOCS = {
    "integrated_deviation": ("1", "|integrated - target| / bbox diagonal per vertex, before reproduction and "
                                  "fallback, (n,) float64"),
    "repaired": ("length", "repaired vertex positions (after the fallback), (n, 3) float64"),
    "deviation": ("1", "|repaired - target| / bbox diagonal per vertex, (n,) float64"),
    "replaced": ("flags", "fallback per vertex: 1 target (key frames pass through, S0 Fig. 9), 2 target (new "
                          "intersection), 4 smoothed, 8 rigid reference (new intersection), 16 reproduced (moved to the "
                          "target, residual blended), 32 pushed (unconstrained, out of a contact the snap makes), "
                          "64 separated (moved apart along the reference's separating axis, new intersection), "
                          "(n,) uint8"),
    "new_faces": ("bool", "faces intersecting in the repaired pose but not in the reference, (m,) bool"),
    "pairs": ("index", "intersecting face pairs (f < g) of the repaired pose, (P, 2) int64"),
}


def build_parser():
    parser = stage_parser("verify", __doc__)
    parser.add_argument("--keyframes", required=True, help="keyframes.h5 of the pose (reference, target, faces)")
    parser.add_argument("--classify", required=True, help="classify.h5 of the pose (V_C, reference intersections)")
    parser.add_argument("--integrate", required=True, help="integrate.h5 of the pose")
    parser.add_argument("--fit", required=True, help="fit.h5 of the pose (eps)")
    parser.add_argument("--out", required=True, help="verify.h5 to write")
    parser.add_argument("--fallback-eps", type=float, default=100.0,
                        help="vertices farther than this many eps from their targets have not reached them")
    parser.add_argument("--fallback-fit", type=float, default=2.0,
                        help="constrained vertices within this many fit max errors (at least the threshold above) of their "
                        "targets are put on them")
    parser.add_argument("--ring", type=int, default=1, help="rings grown around fallback triggers (first attempt)")
    parser.add_argument("--max-rings", type=int, default=6, help="most rings tried around new intersections")
    parser.add_argument("--no-repair-new", dest="repair_new", action="store_false",
                        help="do not replace regions with new intersections by the target")
    parser.add_argument("--no-reproduce", dest="reproduce", action="store_false",
                        help="keep the integrated positions of the constrained vertices (no snap to the target)")
    return parser


def main(args, log):
    timings = Timings()
    with timings.step("read", log):
        kf, _ = read_artifact(args.keyframes, "keyframes", ["reference", "target", "faces"])
        cl, _ = read_artifact(args.classify, "classify", ["mask", "pairs", "pair_offsets"])
        it, _ = read_artifact(args.integrate, "integrate", ["positions"])
        _, fattrs = read_artifact(args.fit, "fit", [])
    V_ref, V_tgt, F = kf["reference"], kf["target"], kf["faces"]
    d = float(fattrs["metrics"]["bbox_diagonal"])
    eps = json.loads(fattrs["config"])["eps_rel"] * d
    m, mask = len(F), cl["mask"]
    frame_pairs = split_frames(cl["pairs"], cl["pair_offsets"])
    reference_faces = intersecting_faces(frame_pairs[0], m)
    target_faces = intersecting_faces(frame_pairs[-1], m)
    keyframes_max = max(intersecting_faces(p, m).sum() for p in frame_pairs)
    threshold = args.fallback_eps * eps  # farther: not reached (pass-through triggers)
    reach = max(threshold, args.fallback_fit * float(fattrs["metrics"]["max_error_rel"]) * d)  # V_C: snap within
    integrated_dev, integrated = deviation(it["positions"], V_tgt, mask, d)
    A = vertex_adjacency(F, len(V_ref))

    def reproduce(X, replaced):
        """Snap the constrained vertices within ``reach`` of their targets, outside fallback regions."""
        if not args.reproduce:
            return X, replaced
        reached = np.linalg.norm(X - V_tgt, axis=1) <= reach
        keep = mask & reached & (replaced == 0)
        X, moved, pushed = reproduce_targets(X, V_tgt, F, A, keep, (replaced > 0) | (mask & ~reached),
                                             reference_faces, log=log)
        return X, replaced | (moved * np.uint8(REPRODUCED)) | (pushed * np.uint8(PUSHED))

    # first, so that the fallback works on the corrected pose: constrained vertices that could not be
    # snapped (that would add intersections) and stay beyond the threshold trigger the pass-through fallback
    with timings.step("reproduce", log):
        X, reproduced = reproduce(it["positions"], np.zeros(len(V_ref), dtype=np.uint8))
    with timings.step("fallback", log):
        X, replaced, _ = fallback(X, V_ref, V_tgt, F, mask, frame_pairs, threshold,
                                  args.ring, args.max_rings, args.repair_new, log)
    with timings.step("reproduce", log):  # again: what the fallback untangled may now be snapped
        X, replaced = reproduce(X, replaced)
        replaced |= reproduced
    with timings.step("verify", log):
        repaired_pairs = self_intersecting_pairs(X, F)
        repaired_faces = intersecting_faces(repaired_pairs, m)
        new = repaired_faces & ~reference_faces
        dev, summary = deviation(X, V_tgt, mask, d)
    metrics = {"vertices": len(X), "faces": m, "intersecting_faces_reference": int(reference_faces.sum()),
               "intersecting_faces_target": int(target_faces.sum()),
               "intersecting_faces_repaired": int(repaired_faces.sum()), "repaired_new": int(new.sum()),
               "intersecting_faces_keyframes_max": int(keyframes_max), **_fallback_counts(replaced, new, F),
               **{f"deviation_{k}": v for k, v in summary.items()},
               **{f"integrated_deviation_{k}": v for k, v in integrated.items()}}
    log.info("intersecting faces: reference %d, target %d, repaired %d (new %d); %d vertices changed by the fallback",
             reference_faces.sum(), target_faces.sum(), repaired_faces.sum(), new.sum(), metrics["fallback_vertices"])
    log.info("deviation / d: constrained mean %.2e max %.2e, free mean %.2e max %.2e (integrated: %.2e, %.2e)",
             summary["constrained_mean"], summary["constrained_max"], summary["free_mean"], summary["free_max"],
             integrated["constrained_mean"], integrated["constrained_max"])
    write_artifact(
        args.out, "verify",
        {"integrated_deviation": integrated_dev, "repaired": X, "deviation": dev, "replaced": replaced,
         "new_faces": new, "pairs": repaired_pairs},
        params={"fallback_eps": args.fallback_eps, "fallback_fit": args.fallback_fit, "ring": args.ring, "max_rings": args.max_rings,
                "repair_new": args.repair_new, "reproduce": args.reproduce},
        inputs=[args.keyframes, args.classify, args.integrate, args.fit], timings=timings, metrics=metrics,
        docs=DOCS)


def _fallback_counts(replaced, new, F):
    """Vertex counts per fallback kind and the new faces inside pass-through regions (metrics)."""
    pass_through = (replaced & REPLACED_PASS_THROUGH) > 0
    snap = np.uint8(REPRODUCED | PUSHED)
    return {"fallback_vertices": int(np.count_nonzero(replaced & ~snap)),
            "fallback_pass_through": int(np.count_nonzero(pass_through)),
            "fallback_new_intersection": int(np.count_nonzero(replaced & ~np.uint8(REPLACED_PASS_THROUGH) & ~snap)),
            "reproduced_vertices": int(np.count_nonzero(replaced & REPRODUCED)),
            "pushed_vertices": int(np.count_nonzero(replaced & PUSHED)),
            "repaired_new_in_fallback": int(new[pass_through[F].any(axis=1)].sum())}


if __name__ == "__main__":
    run_stage(build_parser(), main)
