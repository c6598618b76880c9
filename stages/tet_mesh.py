"""Stage tet_mesh: the coarse tet mesh of the reference (S4 §2.1), once per library.

Quadric decimation, then a Delaunay tetrahedralization kept inside the reference by its winding number
(``posefix.volumetric.tet_mesh``). The volumetric repair (stage repair_volumetric) poses these tets in every
target pose.
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

from posefix.io.artifacts import write_artifact
from posefix.workflow.cli import dataset_docs, run_stage, stage_parser
from posefix.io.errors import InputError
from posefix.io.library import read_welded_reference
from posefix.workflow.timings import Timings
from posefix.volumetric.tet_mesh import tet_mesh
from posefix.workflow.stage_settings import TetMeshSettings


def build_parser():
    return stage_parser("tet_mesh", __doc__, [(TetMeshSettings, "tet mesh (config volumetric.repair)")],
                        reference="reference mesh (.obj/.ply/.off, optionally .gz)", out="tets.h5 to write")


def main(args, log):
    timings = Timings()
    if args.tet_vertices < 4:
        raise InputError("arguments", "need --tet-vertices >= 4")
    with timings.step("read"):
        V, F, _ = read_welded_reference(args.reference)
    with timings.step("tets"):
        X, T = tet_mesh(V, F, args.tet_vertices)
    log.info("%s: %d vertices; tet mesh of %d vertices, %d tets", args.reference, len(V), len(X), len(T))
    params = {k: v for k, v in vars(args).items() if k not in ("log", "out", "threads")}
    write_artifact(args.out, "tet_mesh", {"X": X, "T": T}, params=params, inputs=[args.reference],
                   timings=timings, metrics={"tet_vertices": len(X), "tets": len(T)}, docs=dataset_docs("tet_mesh"))


if __name__ == "__main__":
    run_stage(build_parser(), main)
