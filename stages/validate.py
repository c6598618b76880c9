"""Stage validate: check a whole pose library before any pose is processed.

Reads the reference and every target pose (as trimesh with process=False), and stops at the first
problem with one line naming the file: unreadable or empty file, not a triangle mesh, NaN/inf
coordinates, face indices out of range, degenerate or zero-area reference faces, a vertex count
or face array that differs from the reference. Writes ``library.h5``: the reference mesh and
a manifest (name, path, format, sha256) of every pose.
"""

import posefix  # noqa: F401  (runtime defaults before numpy)
import numpy as np

from posefix.mesh.geometry import bbox_diagonal
from posefix.pipeline.artifacts import write_artifact
from posefix.pipeline.cli import run_stage, stage_parser
from posefix.pipeline.files import file_sha256
from posefix.pipeline.library import discover_library, read_pose, read_reference
from posefix.pipeline.timings import Timings

DOCS = {
    "reference/vertices": ("length", "reference vertex positions, (n, 3) float64"),
    "faces": ("index", "triangle vertex indices shared by all poses, (m, 3) int64, 0-based"),
    "poses/name": ("", "pose names, (p,) UTF-8 str, the reference first"),
    "poses/path": ("", "mesh file paths as given, (p,) UTF-8 str"),
    "poses/format": ("", "file format with compression suffix, e.g. '.obj.gz', (p,) UTF-8 str"),
    "poses/sha256": ("", "sha256 of each file's bytes, (p,) UTF-8 str"),
}


def build_parser():
    parser = stage_parser("validate", __doc__)
    parser.add_argument("--library", required=True, help="folder of the pose library")
    parser.add_argument("--reference", default=None, help="reference file or pose name")
    parser.add_argument("--poses", default=None, help="comma-separated pose names (default: all)")
    parser.add_argument("--name", default=None, help="library name (default: folder name)")
    parser.add_argument("--out", required=True, help="library.h5 to write")
    return parser


def main(args, log):
    timings = Timings()
    poses = [p for p in (args.poses or "").split(",") if p] or None
    library = discover_library(args.library, reference=args.reference, poses=poses, name=args.name)
    log.info("library %s: reference %s, %d poses", library.name, library.reference.name, len(library.poses))
    with timings.step("read"):
        V_ref, F = read_reference(library.reference.path)
        for i, pose in enumerate(library.poses, 1):
            read_pose(pose.path, V_ref, F)
            log.info("pose %d/%d %s: ok", i, len(library.poses), pose.name)
    files = (library.reference,) + library.poses
    with timings.step("hash"):
        sha = [file_sha256(f.path) for f in files]
    write_artifact(
        args.out, "validate",
        {"reference/vertices": V_ref, "faces": F,
         "poses/name": np.array([f.name for f in files]),
         "poses/path": np.array([f.path for f in files]),
         "poses/format": np.array([f.suffix for f in files]),
         "poses/sha256": np.array(sha)},
        params={"library": args.library, "reference": args.reference, "poses": poses, "name": library.name},
        inputs=[f.path for f in files], timings=timings,
        metrics={"vertices": len(V_ref), "faces": len(F), "poses": len(library.poses),
                 "bbox_diagonal": bbox_diagonal(V_ref)},
        docs=DOCS)


if __name__ == "__main__":
    run_stage(build_parser(), main)
