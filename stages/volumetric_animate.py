"""Stage volumetric_animate: animate a reference mesh by motion-capture marker tracks (S4 §3.2).

Builds a coarse tet mesh of the reference, attaches every marker to it as a point handle (by reference
vertex id, or at its position in the first frame, which must then be the rest pose: the markers of S4 §3.2 may sit
slightly outside the surface), and solves every frame with a few iterations of the volumetric editor warm-started from the
previous frame; the surface follows by the editor's transfer (S4 §2.4). Writes the reference and one mesh per frame into one
folder, in the reference's format, faces and vertex order: a pose library the repair workflow reads. The
artifact records the marker residuals per frame.
"""

import argparse
from pathlib import Path

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

import numpy as np

from posefix.mesh.distance import surface_distance_below
from posefix.mesh.geometry import bbox_diagonal
from posefix.io.artifacts import write_artifact
from posefix.workflow.cli import authoring_parser, dataset_docs, run_stage
from posefix.workflow.stage_settings import TetMeshSettings, VolumetricAnimateSettings
from posefix.io.errors import InputError
from posefix.io.library import read_reference
from posefix.io.marker_tracks import read_tracks
from posefix.io.meshes import mesh_file, write_like
from posefix.workflow.timings import Timings
from posefix.volumetric.authoring import region_tets
from posefix.volumetric.markers import MarkerAnimator
from posefix.volumetric.tet_mesh import tet_mesh



def named_box(text):
    """Parse ``"hips=x0,y0,z0,x1,y1,z1"`` into ``("hips", (2, 3) array)`` (argparse type)."""
    name, sep, values = text.partition("=")
    try:
        box = np.array([float(v) for v in values.split(",")]).reshape(2, 3)
    except ValueError:
        box = None
    if not (sep and name) or box is None or (box[0] > box[1]).any():
        raise argparse.ArgumentTypeError(f"not NAME=x0,y0,z0,x1,y1,z1 (min corner, max corner): {text!r}")
    return name, box


def build_parser():
    settings = [(TetMeshSettings, "tet mesh (config volumetric.animate)"),
                (VolumetricAnimateSettings, "animation (config volumetric.animate)")]
    parser = authoring_parser("volumetric_animate", __doc__, settings,
                              ("tracks", "marker tracks: .csv (frame, marker, x, y, z) or .npz"),
                              "the tet mesh, markers and residuals")
    parser.add_argument("--rigid", type=named_box, action="append", default=[], metavar="NAME=x0,y0,z0,x1,y1,z1",
                        help="a rigid region: the tets wholly inside the box (repeatable)")
    return parser


def marker_rest_positions(args, V, F, tracks):
    """Rest positions (p, 3) of the markers and their distances from the surface (p,); :class:`InputError`
    naming the tracks for a label that is no vertex id or a first-frame marker far from the surface."""
    if args.attach == "vertex":
        try:
            ids = np.array([int(m) for m in tracks.markers])
        except ValueError:
            raise InputError(args.tracks, "with --attach vertex, marker labels must be vertex ids") from None
        if ids.min() < 0 or ids.max() >= len(V):
            raise InputError(args.tracks, f"marker label {ids.max() if ids.max() >= len(V) else ids.min()} is no "
                                          f"vertex id of the {len(V)}-vertex reference")
        return V[ids], np.zeros(len(ids))
    limit = args.max_offset * bbox_diagonal(V)
    offsets = surface_distance_below(V, F, tracks.positions[0], np.full(len(tracks.markers), 2.0 * limit))
    far = np.flatnonzero(offsets > limit)
    if len(far):
        raise InputError(args.tracks, f"marker {tracks.markers[far[0]]} is {offsets[far[0]]:.4g} from the reference "
                                      f"surface in the first frame (more than --max-offset {args.max_offset} of the "
                                      "bbox diagonal): with --attach position the first frame must be the rest pose")
    return tracks.positions[0], offsets


def main(args, log):
    timings = Timings()
    if args.tet_vertices < 4 or args.iterations < 0 or args.first_iterations < 0 or args.max_offset < 0:
        raise InputError("arguments", "need --tet-vertices >= 4, --iterations >= 0, --first-iterations >= 0, "
                                      "--max-offset >= 0")
    with timings.step("read"):
        V, F = read_reference(args.mesh)
        tracks = read_tracks(args.tracks)
    if tracks.frames.min() < 0:
        raise InputError(args.tracks, f"frame {tracks.frames.min()}: frame numbers must be >= 0")
    markers, offsets = marker_rest_positions(args, V, F, tracks)
    with timings.step("tets"):
        X, T = tet_mesh(V, F, args.tet_vertices)
    rigid = {name: region_tets(X, T, box) for name, box in args.rigid}
    empty = [name for name, tets in rigid.items() if len(tets) == 0]
    if empty:
        raise InputError("arguments", f"rigid region '{empty[0]}': no tet lies wholly in its box")
    log.info("%s: %d vertices; tet mesh %d vertices, %d tets; %d markers, %d frames", args.mesh, len(V), len(X),
             len(T), len(markers), len(tracks.frames))
    with timings.step("prepare"):
        animator = MarkerAnimator(V, X, T, markers, rigid=list(rigid.values()))
    with timings.step("animate"):
        result = animator.animate(tracks.positions, args.iterations, args.first_iterations)
    d = bbox_diagonal(V)
    log.info("marker residuals on the surface: mean %.3g d, max %.3g d; %.3f s per frame",
             result.residuals.mean() / d, result.residuals.max() / d, result.seconds.mean())
    name = args.name or Path(args.tracks).name.split(".")[0]
    width = max(4, len(str(tracks.frames.max())))
    with timings.step("write"):
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        suffix = mesh_file(args.mesh).suffix
        write_like(out / f"{name}-reference{suffix}", V, F, args.mesh)
        for frame, positions in zip(tracks.frames, result.frames):
            write_like(out / f"{name}-{frame:0{width}d}{suffix}", positions, F, args.mesh)
    datasets = {"tets/X": X, "tets/T": T, "markers": markers, "labels": tracks.markers, "offsets": offsets,
                "frames": tracks.frames, "residuals": result.residuals, "shear": result.shear,
                "seconds": result.seconds}
    metrics = {"frames": len(tracks.frames), "markers": len(markers), "tet_vertices": len(X), "tets": len(T),
               "residual_mean_rel": float(result.residuals.mean() / d),
               "residual_max_rel": float(result.residuals.max() / d),
               "seconds_per_frame": float(result.seconds.mean())}
    params = {k: (v if k != "rigid" else [[n, b.tolist()] for n, b in v]) for k, v in vars(args).items()
              if k not in ("log", "artifact", "threads")}
    write_artifact(args.artifact, "volumetric_animate", datasets, params=params, inputs=[args.mesh, args.tracks],
                   timings=timings, metrics=metrics, docs=dataset_docs("volumetric_animate"))


if __name__ == "__main__":
    run_stage(build_parser(), main)
