"""Stage validate: check the reference, or poses of a library against it, before they are processed.

Reads the reference and the chosen target poses (as trimesh with process=False), and stops at the first
problem with one line naming the file: unreadable or empty file, not a triangle mesh, NaN/inf
coordinates, face indices out of range, degenerate or zero-area reference faces, a reference too small
for the fit, a vertex count or face array that differs from the reference. Writes a manifest (name, path,
format, sha256) of the files read and the reference's measures (vertices, faces, bounding-box diagonal, its own
intersecting faces); the later stages read the meshes from the files. The workflow runs it once for the reference
(``--reference-only``: ``reference.h5``) and once per pose (``--poses <pose>``: ``<pose>/validate.h5``),
so adding or fixing a pose reruns only that pose.
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)
from pathlib import Path

import numpy as np

from posefix.mesh.geometry import bbox_diagonal
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.io.artifacts import write_artifact
from posefix.workflow.cli import dataset_docs, run_stage, stage_parser
from posefix.io.files import file_sha256
from posefix.mesh.weld import Weld
from posefix.io.library import check_seams, discover_library, find_reference, read_pose, read_reference
from posefix.workflow.timings import Timings


def build_parser():
    parser = stage_parser("validate", __doc__, library="folder of the pose library",
                          out="the artifact to write (reference.h5, <pose>/validate.h5)")
    parser.add_argument("--reference", default=None, help="reference file or pose name")
    parser.add_argument("--poses", default=None, help="comma-separated pose names (default: all)")
    parser.add_argument("--name", default=None, help="library name (default: folder name)")
    parser.add_argument("--reference-only", action="store_true", help="read and check the reference alone")
    return parser


def main(args, log):
    timings = Timings()
    poses = [p for p in (args.poses or "").split(",") if p] or None
    if args.reference_only:  # the poses need not be there (a USD or glTF library unpacks them one by one)
        reference, checked = find_reference(args.library, args.reference), ()
        name = args.name or Path(args.library).resolve().name
    else:
        library = discover_library(args.library, reference=args.reference, poses=poses, name=args.name)
        log.info("library %s: reference %s, %d poses", library.name, library.reference.name, len(library.poses))
        reference, checked, name = library.reference, library.poses, library.name
    with timings.step("read"):
        V_ref, F = read_reference(reference.path)
        weld = Weld.of(V_ref, F)
        if weld.split:
            log.info("reference: %d vertices split along seams (welded for the repair, split again on output)",
                     len(weld.index) - len(weld.kept))
        own = _own_intersections(reference.path, V_ref, F, log) if args.reference_only else 0
        for i, pose in enumerate(checked, 1):
            check_seams(pose.path, weld, read_pose(pose.path, V_ref, F), V_ref, F)
            log.info("pose %d/%d %s: ok", i, len(checked), pose.name)
    files = (reference,) + tuple(checked)
    with timings.step("hash"):
        sha = [file_sha256(f.path) for f in files]
    write_artifact(
        args.out, "validate",
        {"poses/name": np.array([f.name for f in files]),
         "poses/path": np.array([f.path for f in files]),
         "poses/format": np.array([f.suffix for f in files]),
         "poses/sha256": np.array(sha)},
        params={"library": args.library, "reference": args.reference, "poses": poses, "name": name,
                "reference_only": args.reference_only},
        inputs=[f.path for f in files], timings=timings,
        metrics={"vertices": len(V_ref), "split_vertices": len(weld.index) - len(weld.kept), "faces": len(F),
                 "poses": len(checked), "reference_intersecting_faces": own,
                 "bbox_diagonal": bbox_diagonal(V_ref)},
        docs=dataset_docs("validate"))


def _own_intersections(path, V, F, log):
    """The reference's intersecting faces (the exact detector), said on the terminal when there are any (int)."""
    faces = int(intersecting_faces(self_intersecting_pairs(V, F), len(F)).sum())
    if faces:
        log.warning("%s: the reference has %d intersecting faces: allowed (the repairs tolerate them and form no "
                    "new intersection)", path, faces)
    return faces


if __name__ == "__main__":
    run_stage(build_parser(), main)
