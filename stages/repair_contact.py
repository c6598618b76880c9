"""Stage repair_contact: the contact repair of one pose (IPC), another repair beside the space-time repair.

The contact solver (``posefix.mesh.contact_solver``, ipctk) carries the reference through the pose's key
frames (stage keyframes) to the target; every step is bounded by continuous collision detection, so no
intersection that the reference does not have can form (the reference's own, from stage classify, are
tolerated). See ``posefix.contact.keyframe_tracking``.
"""

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)
from dataclasses import asdict

from posefix.contact.keyframe_tracking import track_keyframes
from posefix.mesh.contact_solver import ContactSettings, ContactSolver
from posefix.mesh.geometry import unit_scale
from posefix.mesh.intersections import intersecting_faces
from posefix.io.artifacts import read_artifact, write_artifact
from posefix.io.keyframes import read_keyframes
from posefix.workflow.cli import dataset_docs, run_stage, stage_parser
from posefix.workflow.settings import settings_from
from posefix.workflow.timings import Timings
from posefix.spacetime.classification import split_frames


def build_parser():
    return stage_parser("repair_contact", __doc__, [(ContactSettings, "contact solver (config contact)")],
                        keyframes="keyframes.h5 of the pose (frames, faces)",
                        classify="classify.h5 of the pose (the reference's intersections)", out="contact.h5 to write")


def main(args, log):
    timings = Timings()
    with timings.step("read"):
        kf, _ = read_keyframes(args.keyframes, ["frames", "faces"])
        cl, _ = read_artifact(args.classify, "classify", ["pairs", "pair_offsets"])
    frames, F = kf["frames"], kf["faces"]  # the reference first, the target last
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
                   {"repaired": result.X / unit, "contact": result.contact,
                    "new_faces": result.new_faces},
                   params=params, inputs=[args.keyframes, args.classify], timings=timings, metrics=metrics,
                   docs=dataset_docs("repair_contact"))


if __name__ == "__main__":
    run_stage(build_parser(), main)
