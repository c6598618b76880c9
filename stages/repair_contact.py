"""Stage repair_contact: the contact repair of one pose (IPC), another repair beside the space-time repair.

The contact solver (``posefix.mesh.contact_solver``, ipctk) carries the reference through the pose's key
frames (stage keyframes) to the target; every step is bounded by continuous collision detection, so no
intersection that the reference does not have can form (the reference's own, from stage classify, are
tolerated). See ``posefix.contact.keyframe_tracking``.
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)
from dataclasses import asdict

import numpy as np

from posefix.contact.keyframe_tracking import track_keyframes
from posefix.mesh.contact_solver import ContactSettings, ContactSolver
from posefix.mesh.geometry import unit_scale
from posefix.mesh.intersections import intersecting_faces
from posefix.io.artifacts import read_artifact, write_artifact
from posefix.workflow.cli import run_stage, stage_parser
from posefix.workflow.settings import add_settings_options, settings_from
from posefix.workflow.timings import Timings
from posefix.spacetime.classification import split_frames

DOCS = {
    "start": ("length", "the target pose (the last key frame, exactly), (n, 3) float64"),
    "repaired": ("length", "the repaired pose: the reference carried through the key frames, (n, 3) float64"),
    "contact": ("bool", "vertices the barrier holds off the target (closer than dhat to a part they do not touch "
                        "in the reference), (n,) bool"),
    "new_faces": ("bool", "faces intersecting in the repaired pose but not in the reference, (m,) bool"),
}


def build_parser():
    parser = stage_parser("repair_contact", __doc__)
    parser.add_argument("--keyframes", required=True, help="keyframes.h5 of the pose (frames, faces)")
    parser.add_argument("--classify", required=True, help="classify.h5 of the pose (the reference's intersections)")
    parser.add_argument("--out", required=True, help="contact.h5 to write")
    add_settings_options(parser, ContactSettings, "contact solver (config contact)")
    return parser


def main(args, log):
    timings = Timings()
    with timings.step("read"):
        kf, _ = read_artifact(args.keyframes, "keyframes", ["frames", "faces", "reference", "target"])
        cl, _ = read_artifact(args.classify, "classify", ["pairs", "pair_offsets"])
    frames, F = np.concatenate([kf["reference"][None], kf["frames"][1:-1], kf["target"][None]]), kf["faces"]
    unit = unit_scale(frames[0])  # the working unit: a library at 1e-30 or 1e+30 repairs as at 1
    reference_pairs = split_frames(cl["pairs"], cl["pair_offsets"])[0]
    reference_faces = intersecting_faces(reference_pairs, len(F))
    settings = settings_from(vars(args), ContactSettings)
    params = asdict(settings)
    with timings.step("prepare"):
        solver = ContactSolver(unit * frames[0], F, reference_pairs, settings)
    with timings.step("repair"):
        result = track_keyframes(solver, unit * frames, reference_faces)
    metrics = result.metrics | {"intersecting_faces_reference": int(reference_faces.sum()),
                                "intersecting_faces_repaired": int(result.faces.sum()),
                                "intersecting_faces_repaired_new": int(result.new_faces.sum()),
                                "seconds": timings["prepare"] + timings["repair"]}
    write_artifact(args.out, "repair_contact",
                   {"start": frames[-1], "repaired": result.X / unit, "contact": result.contact,
                    "new_faces": result.new_faces},
                   params=params, inputs=[args.keyframes, args.classify], timings=timings, metrics=metrics, docs=DOCS)


if __name__ == "__main__":
    run_stage(build_parser(), main)
