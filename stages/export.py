"""Stage export: write the repaired pose (space-time's, or another repair's) in the target's own file format.

Same format and compression as the target file, identical faces and vertex order; for OBJ the
target's text is kept line by line except for the vertex (and per-vertex normal) lines (see
``posefix.io.meshes.write_like``).
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)
import numpy as np

from posefix.io.artifacts import read_artifact
from posefix.workflow.cli import run_stage, stage_parser
from posefix.io.errors import InputError
from posefix.io.library import read_welded_reference
from posefix.io.meshes import read_mesh, write_like
from posefix.workflow.timings import Timings


def build_parser():
    parser = stage_parser("export", __doc__,
                          artifact="verify.h5 (space-time) or another repair's artifact of the pose",
                          reference="the reference mesh file (its seams: vertices split there get one position again)",
                          target="the target mesh file (its format is reproduced)",
                          out="repaired mesh file (same extension as --target)")
    parser.add_argument("--stage", default="verify", choices=("verify", "repair_medial", "repair_volumetric", "repair_contact"),
                        help="the stage that wrote --artifact: its dataset 'repaired' is written")
    return parser


def main(args, log):
    timings = Timings()
    with timings.step("read"):
        data, _ = read_artifact(args.artifact, args.stage, ["repaired"])
        V_tgt, F = read_mesh(args.target)
        _, _, weld = read_welded_reference(args.reference)
    if len(data["repaired"]) != len(weld.kept):
        raise InputError(args.artifact, f"{len(data['repaired'])} vertices, the welded reference has {len(weld.kept)}")
    X = weld.unweld(data["repaired"])
    if X.shape != V_tgt.shape:
        raise InputError(args.target, f"{len(V_tgt)} vertices, the repaired pose has {len(X)}")
    with timings.step("write"):
        write_like(args.out, X, F, args.target)
    V_back, F_back = read_mesh(args.out)
    if not (np.array_equal(F_back, F) and np.array_equal(V_back, X)):
        raise InputError(args.out, "did not read back as written")  # never expected; checked to be sure
    log.info("wrote %s (%d vertices, %d faces)", args.out, len(X), len(F))


if __name__ == "__main__":
    run_stage(build_parser(), main)
