"""Stage repair_volumetric: the volumetric repair of one pose (the volumetric editor, S4 §2), compared beside space-time.

The target's V_C vertices (stage classify) become point handles of the reference's tet mesh (stage
tet_mesh) at their target positions; the editor's iterations fill the free region, its transfer (S4 §2.4) gives the
surface.
The free region grows by rings until no new self-intersection remains (intersections the reference has
too do not count). See ``posefix.volumetric.repair``.
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

from posefix.io.artifacts import read_artifact, write_artifact
from posefix.workflow.cli import dataset_docs, run_stage, stage_parser
from posefix.io.errors import InputError
from posefix.io.library import read_welded_pair
from posefix.workflow.timings import Timings
from posefix.volumetric.repair import VolumetricRepair
from posefix.workflow.stage_settings import VolumetricRepairSettings


def build_parser():
    return stage_parser("repair_volumetric", __doc__,
                        [(VolumetricRepairSettings, "volumetric repair (config volumetric.repair)")],
                        reference="reference mesh file", target="target pose file",
                        classify="classify.h5 of the pose (its mask is V_C)",
                        tets="tets.h5 of the reference (stage tet_mesh)", out="volumetric.h5 to write")


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
    datasets = {"repaired": result.X, "free": result.free, "tets": result.tets,
                "shear": result.shear}
    metrics = {"iterations": args.iterations, "rings": result.rings, "seconds": result.seconds,
               "free_vertices": int(result.free.sum()), "residual": result.residual,
               "intersecting_faces_target": result.target_faces,
               "intersecting_faces_repaired": int(result.faces.sum()),
               "intersecting_faces_repaired_new": final}
    params = {k: v for k, v in vars(args).items() if k not in ("log", "out", "threads")}
    write_artifact(args.out, "repair_volumetric", datasets, params=params,
                   inputs=[args.reference, args.target, args.classify, args.tets], timings=timings,
                   metrics=metrics, docs=dataset_docs("repair_volumetric"))


if __name__ == "__main__":
    run_stage(build_parser(), main)
