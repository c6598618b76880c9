"""Stage unpack: one pose of a USD or glTF pose library as a mesh file, for the stages that follow.

Writes the pose's points (float64, exactly as the file holds them) and the mesh's triangles as binary PLY
(``posefix.io.containers``: frames, blend shapes or morph targets become poses; polygons become fans of
triangles). The reference is checked here, so that its problems name the container and the prim.
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

from posefix.io.containers import open_container
from posefix.io.library import check_reference
from posefix.io.meshes import write_mesh
from posefix.workflow.cli import run_stage, stage_parser
from posefix.workflow.timings import Timings


def build_parser():
    parser = stage_parser("unpack", __doc__, container="the .usd/.usda/.usdc/.usdz or .gltf/.glb file",
                          pose="the pose's name (posefix.io.containers: frame, shape, target)",
                          out="the mesh file to write (.ply)")
    parser.add_argument("--mesh", default=None, help="its mesh holding the poses (USD prim path, glTF mesh name); "
                                                     "default: the only one")
    parser.add_argument("--reference", action="store_true", help="the pose is the reference: check it as one")
    return parser


def main(args, log):
    timings = Timings()
    with timings.step("read"):
        box = open_container(args.container, args.mesh)
        P = box.points(args.pose)
    if args.reference:
        check_reference(f"{args.container} ({box.where(args.pose)})", P, box.faces)
    with timings.step("write"):
        write_mesh(args.out, P, box.faces)
    log.info("%s: %s -> %s (%d points, %d triangles)", args.container, box.where(args.pose), args.out, len(P),
             len(box.faces))


if __name__ == "__main__":
    run_stage(build_parser(), main)
