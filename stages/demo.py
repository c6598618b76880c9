"""Stage demo: write the built-in demo pose library (a skinned capsule limb) as mesh files.

The reference and four target poses bent 120-150 degrees by linear blend skinning, each in its
own file format (.obj, .ply, .off.gz, .obj.gz) so that a demo run exercises every reader/writer.
Deterministic: the same seed gives byte-identical files.
"""

from pathlib import Path

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.workflow import demo
from posefix.workflow.cli import run_stage, stage_parser
from posefix.workflow.stage_settings import DemoSettings
from posefix.io.meshes import write_mesh
from posefix.workflow.timings import Timings


def build_parser():
    return stage_parser("demo", __doc__, [(DemoSettings, "demo library (config demo)")],
                        out="folder to write the library into")


def main(args, log):
    timings = Timings()
    with timings.step("generate"):
        V_ref, F, poses = demo.demo_library(seed=args.seed, around=args.around)
    log.info("demo limb: %d vertices, %d faces, %d poses", len(V_ref), len(F), len(poses))
    out = Path(args.out)
    with timings.step("write"):
        write_mesh(out / f"{demo.REFERENCE_NAME}{demo.REFERENCE_SUFFIX}", V_ref, F)
        for pose in demo.POSES:
            V = poses[pose.name]
            hits = intersecting_faces(self_intersecting_pairs(V, F), len(F)).sum()
            write_mesh(out / f"{pose.name}{pose.suffix}", V, F)
            log.info("%s%s: %d self-intersecting faces", pose.name, pose.suffix, hits)


if __name__ == "__main__":
    run_stage(build_parser(), main)
