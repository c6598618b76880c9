"""Stage skeletal_pose: author a pose library from a reference mesh and a rig (skeleton-driven deformation, S1 §2-4).

Builds the skeletal mesh of the reference (medial balls, S1 §2), poses it with the rig's linear blend
skinning, and writes every pose of the rig file in three variants (``<pose>-ssd``: skinning of the mesh;
``<pose>-variational``: the reconstruction of S1 §3; ``<pose>-flow``: then the medial-ball flow of S1 §4)
into one folder, with the reference, in the reference's file format, faces and vertex order: a pose
library the repair workflow reads (``snakemake --config library=<folder>``). The artifact records the
skeletal mesh, intersecting faces, the flow's error sum |f| (S1 §4) and seconds per pose and variant, and the flow's
history.
"""

from pathlib import Path

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

import numpy as np

from posefix.mesh.geometry import bbox_diagonal
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.io.artifacts import write_artifact
from posefix.workflow.cli import authoring_parser, dataset_docs, run_stage
from posefix.workflow.stage_settings import SkeletalPoseSettings
from posefix.io.library import read_reference
from posefix.io.meshes import mesh_file, write_like
from posefix.medial.rig_files import read_rig
from posefix.workflow.skeleton_options import add_skeleton_options, reference_skeleton
from posefix.workflow.timings import Timings
from posefix.medial.authoring import VARIANTS, SkeletalPoser, union_error


def build_parser():
    parser = authoring_parser("skeletal_pose", __doc__, [(SkeletalPoseSettings, "authoring (config medial.pose)")],
                              ("rig", "rig file (YAML: joints and poses, see examples/demo-limb.yaml)"),
                              "the skeletal mesh and the metrics")
    add_skeleton_options(parser)
    return parser


def main(args, log):
    timings = Timings()
    with timings.step("read"):
        V, F = read_reference(args.mesh)
        rig, poses = read_rig(args.rig)
    name = args.name or Path(args.rig).name.split(".")[0]
    log.info("%s: %d vertices, %d faces; rig %s: %d joints, %d poses", args.mesh, len(V), len(F), args.rig,
             len(rig.names), len(poses))
    with timings.step("skeleton"):
        skeleton = reference_skeleton(args.mesh, V, F, args)
    with timings.step("prepare"):
        poser = SkeletalPoser(V, F, skeleton.S, rig, args.falloff, args.min_sine, args.min_area)
    margin = bbox_diagonal(V) * args.margin
    rows = [_author(poser, pose, pose_name, args, margin, timings, log) for pose_name, pose in poses.items()]
    with timings.step("write"):
        _write_library(args, name, V, F, poses, rows)
        _write_artifact(args, skeleton, poses, rows, timings)


def _author(poser, pose, pose_name, args, margin, timings, log):
    """Author one pose: its variants' positions, metrics and the flow's history."""
    with timings.step(f"pose {pose_name}"):
        authored = poser.author(pose, margin, args.tau, args.neighbours, args.max_iters)
        F, flow = poser.F, authored.flow
        ssd = int(intersecting_faces(self_intersecting_pairs(authored.positions["ssd"], F), len(F)).sum())
        counts = [ssd, int(flow.intersecting[0]), int(flow.intersecting[flow.best])]  # the flow counted the others
        errors = [union_error(authored.positions[v], authored.S_d, poser.reconstruction.R) for v in VARIANTS]
    log.info("%s: intersecting faces ssd %d, variational %d, flow %d (%d iterations); sum|f| %.4g, %.4g, %.4g",
             pose_name, *counts, flow.iterations, *errors)
    return {"positions": authored.positions, "flow": flow, "intersecting": counts, "error": errors,
            "seconds": [authored.seconds[v] for v in VARIANTS]}


def _write_library(args, name, V, F, poses, rows):
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    suffix = mesh_file(args.mesh).suffix
    write_like(out / f"{name}-reference{suffix}", V, F, args.mesh)
    for pose_name, row in zip(poses, rows):
        for variant in VARIANTS:
            write_like(out / f"{pose_name}-{variant}{suffix}", row["positions"][variant], F, args.mesh)


def _write_artifact(args, skeleton, poses, rows, timings):
    datasets = {
        "skeleton/S": skeleton.S, "skeleton/R": skeleton.R,
        "skeleton/source": np.asarray(skeleton.source, dtype=np.int8), "skeleton/bad": skeleton.bad,
        "poses": np.array(list(poses)), "variants": np.array(VARIANTS),
        "intersecting": np.array([r["intersecting"] for r in rows], dtype=np.int64),
        "error": np.array([r["error"] for r in rows]), "seconds": np.array([r["seconds"] for r in rows]),
    }
    for pose_name, row in zip(poses, rows):
        flow = row["flow"]
        datasets[f"flow/{pose_name}/intersecting"] = flow.intersecting
        datasets[f"flow/{pose_name}/error"] = flow.error
        datasets[f"flow/{pose_name}/step_seconds"] = flow.step_seconds
    params = {k: v for k, v in vars(args).items() if k not in ("log", "artifact", "threads")}
    metrics = {f"skeleton_{k}": v for k, v in skeleton.stats.items() if np.isscalar(v)}
    write_artifact(args.artifact, "skeletal_pose", datasets, params=params, inputs=[args.mesh, args.rig],
                   timings=timings, metrics=metrics, docs=dataset_docs("skeletal_pose"))


if __name__ == "__main__":
    run_stage(build_parser(), main)
