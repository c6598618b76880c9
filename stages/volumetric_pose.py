"""Stage volumetric_pose: author a pose library from a reference mesh and a pose script (volumetric editing, S4 §2).

Builds a coarse tet mesh of the reference (decimated surface, tetrahedralized), resolves the script's handles
and rigid regions on it, and poses it with the iterative volumetric editor (S4 §2.3) for every pose of the script; the surface
follows the tets by the editor's smooth transfer (S4 §2.4, Wendland-blended barycentric coordinates). Writes the
reference and one mesh per pose into one folder, in the reference's format, faces and vertex order: a pose
library the repair workflow reads. The artifact records the tet mesh, its posed vertices, the shear history
and seconds per pose.
"""

from pathlib import Path

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

import numpy as np

from posefix.io.artifacts import write_artifact
from posefix.workflow.cli import authoring_parser, dataset_docs, run_stage
from posefix.workflow.stage_settings import TetMeshSettings, VolumetricPoseSettings
from posefix.io.errors import InputError
from posefix.io.library import read_reference
from posefix.io.meshes import mesh_file, write_like
from posefix.io.pose_scripts import read_pose_script
from posefix.workflow.timings import Timings
from posefix.volumetric.authoring import VolumetricPoser, region_tets
from posefix.volumetric.tet_mesh import tet_mesh


def build_parser():
    settings = [(TetMeshSettings, "tet mesh (config volumetric.pose)"),
                (VolumetricPoseSettings, "authoring (config volumetric.pose)")]
    return authoring_parser("volumetric_pose", __doc__, settings,
                            ("script", "pose script (YAML: handles, rigid, poses)"), "the tet mesh and the metrics")


def _handles(path, script, V, X, T):
    """Region handles and rigid regions as tet ids ({"handle": ..., "rigid region": ...}), point handles as
    rest positions; :class:`InputError` naming the script for an empty box or an unknown vertex id."""
    regions = {"handle": {}, "rigid region": {}}
    points = {}
    boxes = [("handle", n, spec) for n, (kind, spec) in script.handles.items() if kind == "box"]
    for kind, name, box in boxes + [("rigid region", n, b) for n, b in script.rigid.items()]:
        regions[kind][name] = region_tets(X, T, box)
        if len(regions[kind][name]) == 0:
            raise InputError(path, f"{kind} '{name}': no tet lies wholly in its box")
    for name, (kind, spec) in script.handles.items():
        if kind == "vertices":
            if spec.max() >= len(V):
                raise InputError(path, f"handle '{name}': vertex id {spec.max()} >= {len(V)} vertices")
            points[name] = V[spec]
        elif kind == "points":
            points[name] = spec
    return regions, points


def main(args, log):
    timings = Timings()
    if args.tet_vertices < 4 or args.iterations < 0 or args.frames < 1:
        raise InputError("arguments", "need --tet-vertices >= 4, --iterations >= 0, --frames >= 1")
    with timings.step("read"):
        V, F = read_reference(args.mesh)
        script = read_pose_script(args.script)
    with timings.step("tets"):
        X, T = tet_mesh(V, F, args.tet_vertices)
    log.info("%s: %d vertices; tet mesh %d vertices, %d tets", args.mesh, len(V), len(X), len(T))
    regions, points = _handles(args.script, script, V, X, T)
    with timings.step("prepare"):
        poser = VolumetricPoser(V, X, T, regions["handle"], regions["rigid region"], points)
    authored = {}
    for pose, moves in script.poses.items():
        with timings.step(f"pose {pose}"):
            authored[pose] = poser.pose(moves, args.iterations, args.frames)
        log.info("%s: shear %.3g after %d frames, %.2f s", pose, authored[pose].edit.shear[-1], args.frames,
                 authored[pose].seconds)
    name = args.name or Path(args.script).name.split(".")[0]
    with timings.step("write"):
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        suffix = mesh_file(args.mesh).suffix
        write_like(out / f"{name}-reference{suffix}", V, F, args.mesh)
        for pose, result in authored.items():
            write_like(out / f"{pose}{suffix}", result.positions, F, args.mesh)
        datasets = {"tets/X": X, "tets/T": T, "poses": np.array(list(authored)),
                    "posed": np.stack([a.edit.X for a in authored.values()]),
                    "shear": np.array([a.edit.shear[-1] for a in authored.values()]),
                    "seconds": np.array([a.seconds for a in authored.values()])}
        params = {k: v for k, v in vars(args).items() if k not in ("log", "artifact", "threads")}
        write_artifact(args.artifact, "volumetric_pose", datasets, params=params, inputs=[args.mesh, args.script],
                       timings=timings, metrics={"tet_vertices": len(X), "tets": len(T)},
                       docs=dataset_docs("volumetric_pose"))


if __name__ == "__main__":
    run_stage(build_parser(), main)
