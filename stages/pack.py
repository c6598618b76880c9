"""Stage pack: the repaired poses of one repair written back into the USD or glTF file they came from.

The same prims, names, frames and morph targets as the input; only the repaired poses' positions change (blend
shapes and morph targets as offsets from the base). Poses without a repaired mesh (not repaired in this run, or
failed) keep the input's positions and are listed in the log. The file is read back: a pose whose rounding to the
file's float32 would make a face intersect is an error (the contact solver keeps every pair farther apart than that
rounding, ``ContactSolver.keep_gap``).
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)
import os
import tempfile

import numpy as np

from posefix.io.containers import open_container
from posefix.io.errors import InputError
from posefix.io.meshes import read_mesh
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.workflow.cli import run_stage, stage_parser
from posefix.workflow.timings import Timings


def build_parser():
    parser = stage_parser("pack", __doc__, container="the input .usd/.usda/.usdc/.usdz or .gltf/.glb file",
                          repaired="folder of the repair's meshes, <pose>.ply",
                          out="the container to write (the input's extension)")
    parser.add_argument("--mesh", default=None, help="its mesh holding the poses (USD prim path, glTF mesh name)")
    parser.add_argument("--poses", default="", help="comma-separated names of the repaired poses to write")
    return parser


def main(args, log):
    timings = Timings()
    if os.path.splitext(args.out)[1].lower() != os.path.splitext(args.container)[1].lower():
        raise InputError(args.out, f"must have the extension of {args.container}")
    with timings.step("read"):
        box = open_container(args.container, args.mesh)
        positions = {pose: _repaired(box, os.path.join(args.repaired, f"{pose}.ply"))
                     for pose in filter(None, args.poses.split(","))}
    with timings.step("write"), tempfile.TemporaryDirectory(dir=os.path.dirname(os.path.abspath(args.out))) as tmp:
        written = os.path.join(tmp, os.path.basename(args.out))  # the same name: a container names poses by it
        box.write(written, positions)
        back = open_container(written, box.mesh)
        for pose, X in positions.items():
            _check_read_back(args.out, back, pose, X)
        os.replace(written, args.out)
    kept = [m for m in box.members if m not in positions and m != box.rest]
    log.info("wrote %s: %d poses repaired%s", args.out, len(positions),
             f", {len(kept)} as in the input ({', '.join(kept[:5])}{' ...' if len(kept) > 5 else ''})" if kept else "")


def _check_read_back(out, back, pose, X):
    """InputError unless ``pose`` of the written container ``back`` (at ``out``) holds ``X`` (n, 3) up to its
    rounding (float32) and that rounding made no face intersect (the exact detector on the file as read back)."""
    P = back.points(pose)
    if not np.allclose(P, X, rtol=0, atol=1e-6 * (1 + np.abs(X).max())):
        raise InputError(out, f"{back.where(pose)} did not read back as written")
    if np.array_equal(P, X):
        return
    m = len(back.faces)
    new = (intersecting_faces(self_intersecting_pairs(P, back.faces), m)
           & ~intersecting_faces(self_intersecting_pairs(X, back.faces), m))
    if new.any():
        raise InputError(out, f"{back.where(pose)}: rounded to the file's float32, {new.sum()} faces intersect that "
                              "do not in the repaired mesh")


def _repaired(box, path):
    """The repaired positions (n, 3) in ``path``; InputError unless it has the container's points and faces."""
    V, F = read_mesh(path)
    if len(V) != box.n or not np.array_equal(F, box.faces):
        raise InputError(path, f"not a pose of {box.path} ({len(V)} points, {len(F)} triangles; the mesh has "
                               f"{box.n}, {len(box.faces)})")
    return V


if __name__ == "__main__":
    run_stage(build_parser(), main)
