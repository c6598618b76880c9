"""Stage repair_volumetric: the volumetric repair of one pose (the volumetric editor, S4 §2), compared beside space-time.

The target's V_C vertices (stage classify) become point handles of the reference's tet mesh (stage
tet_mesh) at their target positions; the editor's iterations fill the free region, its transfer (S4 §2.4) gives the
surface.
The free region grows by rings until no new self-intersection remains (intersections the reference has
too do not count). See ``posefix.volumetric.repair``.
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

from posefix.io.artifacts import read_artifact, write_artifact
from posefix.workflow.cli import run_stage, stage_parser
from posefix.workflow.settings import add_settings_options
from posefix.io.errors import InputError
from posefix.io.library import read_welded_pair
from posefix.workflow.timings import Timings
from posefix.volumetric.repair import VolumetricRepair
from posefix.workflow.stage_settings import VolumetricRepairSettings

DOCS = {
    "start": ("length", "the target pose, (n, 3) float64"),
    "repaired": ("length", "the filled pose: the target on the kept vertices, (n, 3) float64"),
    "free": ("bool", "the vertices filled: not V_C, grown by 'rings' rings, (n,) bool"),
    "tets": ("length", "the posed tet-mesh vertices, (k, 3) float64"),
    "shear": ("ratio", "volume-weighted mean |T_j - R_j| of the tets after every solve, (iterations+1,) float64"),
}


def build_parser():
    parser = stage_parser("repair_volumetric", __doc__)
    parser.add_argument("--reference", required=True, help="reference mesh file")
    parser.add_argument("--target", required=True, help="target pose file")
    parser.add_argument("--classify", required=True, help="classify.h5 of the pose (its mask is V_C)")
    parser.add_argument("--tets", required=True, help="tets.h5 of the reference (stage tet_mesh)")
    parser.add_argument("--out", required=True, help="volumetric.h5 to write")
    add_settings_options(parser, VolumetricRepairSettings, "volumetric repair (config volumetric.repair)")
    return parser


def main(args, log):
    timings = Timings()
    if args.iterations < 0 or args.point_weight <= 0 or args.max_rings < 0 or not 0 < args.max_free <= 1:
        raise InputError("arguments", "need --iterations >= 0, --point-weight > 0, --max-rings >= 0, "
                                      "0 < --max-free <= 1")
    with timings.step("read"):
        V, X, F, _ = read_welded_pair(args.reference, args.target)
        mask = read_artifact(args.classify, "classify", ["mask"])[0]["mask"].astype(bool)
        tets, _ = read_artifact(args.tets, "tet_mesh", ["X", "T"])
    if mask.shape != (len(V),):
        raise InputError(args.classify, f"a mask of {len(mask)} vertices for a reference of {len(V)}")
    if not mask.any():
        raise InputError(args.classify, "V_C is empty: nothing holds the tets")
    with timings.step("prepare"):
        fill = VolumetricRepair(V, F, tets["X"], tets["T"])
    with timings.step("repair"):
        result = fill.repair(X, mask, args.iterations, args.point_weight, args.max_rings, args.max_free)
    final = int(result.new_faces.sum())
    log.info("new intersecting faces: target %d, filled %d (%d free vertices, %d rings), V_C residual spread "
             "%.3g, %.2f s", result.target_faces, final, result.free.sum(), result.rings, result.residual,
             result.seconds)
    datasets = {"start": X, "repaired": result.X, "free": result.free, "tets": result.tets,
                "shear": result.shear}
    metrics = {"iterations": args.iterations, "rings": result.rings, "seconds": result.seconds,
               "free_vertices": int(result.free.sum()), "residual": result.residual,
               "intersecting_faces_target": result.target_faces,
               "intersecting_faces_repaired": int(result.faces.sum()),
               "intersecting_faces_repaired_new": final}
    params = {k: v for k, v in vars(args).items() if k not in ("log", "out", "threads")}
    write_artifact(args.out, "repair_volumetric", datasets, params=params,
                   inputs=[args.reference, args.target, args.classify, args.tets], timings=timings,
                   metrics=metrics, docs=DOCS)


if __name__ == "__main__":
    run_stage(build_parser(), main)
