"""Stage classify: self-intersections of every key frame and the constrained vertex set V_C (S0 §4.1).

Detects intersecting face pairs (exact predicates, pairs sharing a vertex not counted) in each
key frame, optionally near contacts, and removes from V_C the vertices of intersecting faces plus
``--ring`` rings, contacts plus rings, and hand-picked vertices; vertices of faces that already
intersect in the reference are added back (S0 §4.3). See ``posefix.spacetime.classification``.
"""

import time

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)
import numpy as np

from posefix.mesh.contacts import contact_vertices
from posefix.mesh.geometry import bbox_diagonal
from posefix.mesh.intersections import intersecting_faces, new_pairs, self_intersecting_pairs
from posefix.io.artifacts import write_artifact
from posefix.io.keyframes import read_keyframes
from posefix.workflow.cli import dataset_docs, int_list, run_stage, stage_parser
from posefix.io.errors import InputError
from posefix.io.library import read_vertex_ids
from posefix.workflow.timings import Timings
from posefix.spacetime.classification import constraint_mask
from posefix.workflow.stage_settings import ClassifySettings


def build_parser():
    parser = stage_parser("classify", __doc__, [(ClassifySettings, "classification (config classify)")],
                          keyframes="keyframes.h5 of the pose", out="classify.h5 to write")
    parser.add_argument("--exclude", type=int_list, default=[], help="vertex ids to exclude by hand, e.g. 1,2,3")
    parser.add_argument("--exclude-file", default=None, help="text file of vertex ids to exclude by hand")
    return parser


def main(args, log):
    timings = Timings()
    if args.ring < 0 or args.contact < 0 or args.contact_radius <= 0:
        raise InputError("arguments", "--ring and --contact must be >= 0, --contact-radius > 0")
    with timings.step("read"):
        data, _ = read_keyframes(args.keyframes, ["frames", "faces", "reference", "weld_index"])
    frames, F, V_ref = data["frames"], data["faces"], data["reference"]
    n, K = len(V_ref), len(frames)
    exclude = data["weld_index"][_exclusions(args, len(data["weld_index"]))]  # input vertex ids -> welded
    frame_pairs = []
    with timings.step("intersections"):
        for k, V in enumerate(frames):
            start = time.perf_counter()
            frame_pairs.append(self_intersecting_pairs(V, F))
            log.info("frame %d/%d: %d intersecting faces (%.2f s)", k + 1, K,
                     intersecting_faces(frame_pairs[-1], len(F)).sum(), time.perf_counter() - start)
    contacts = None
    if args.contact > 0:
        d = bbox_diagonal(V_ref)
        with timings.step("contacts"):
            contacts = contact_vertices(frames, F, V_ref, args.contact * d, args.contact_radius * d)
    with timings.step("mask"):
        mask, reasons = constraint_mask(F, n, frame_pairs, ring=args.ring, contacts=contacts, exclude=exclude)
    counts = np.array([intersecting_faces(p, len(F)).sum() for p in frame_pairs])
    new = np.array([intersecting_faces(new_pairs(p, frame_pairs[0]), len(F)).sum() for p in frame_pairs])
    log.info("V_C: %d of %d vertices (%.1f %%); intersecting faces: reference %d, target %d, max %d",
             mask.sum(), n, 100.0 * mask.mean(), counts[0], counts[-1], counts.max())
    write_artifact(
        args.out, "classify",
        {"pairs": np.concatenate(frame_pairs).reshape(-1, 2),
         "pair_offsets": np.concatenate([[0], np.cumsum([len(p) for p in frame_pairs])]),
         "intersecting_faces": counts, "new_intersecting_faces": new,
         "contact_vertices": contacts.sum(axis=1) if contacts is not None else np.zeros(K, dtype=np.int64),
         "mask": mask, "reasons": reasons},
        params={"ring": args.ring, "contact": args.contact, "contact_radius": args.contact_radius,
                "exclude": sorted(set(int(i) for i in exclude))},
        inputs=[args.keyframes] + ([args.exclude_file] if args.exclude_file else []), timings=timings,
        metrics={"constraint_vertices": int(mask.sum()), "vertices": n,
                 "intersecting_faces_reference": int(counts[0]), "intersecting_faces_target": int(counts[-1]),
                 "intersecting_faces_keyframes_max": int(counts.max()),
                 "new_intersecting_faces_keyframes_max": int(new.max())},
        docs=dataset_docs("classify"))


def _exclusions(args, n):
    """Hand-picked vertex ids (of the input meshes) from ``--exclude`` and ``--exclude-file``, range-checked."""
    ids = np.asarray(args.exclude, dtype=np.int64)
    source = "--exclude"
    if args.exclude_file:
        ids = np.concatenate([ids, read_vertex_ids(args.exclude_file)])
        source = args.exclude_file
    bad = ids[(ids < 0) | (ids >= n)]
    if len(bad):
        raise InputError(source, f"vertex id {bad[0]} out of range 0..{n - 1}")
    return ids


if __name__ == "__main__":
    run_stage(build_parser(), main)
