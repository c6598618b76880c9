"""Stage viewer: the 3D viewer page of a library, ``reports/<library>/viewer.html``.

Reads ``summary.json`` (the poses, their status and other repairs) and each pose's ``keyframes.h5``,
``classify.h5``, ``verify.h5`` and the other repairs' artifacts under ``--results``, and writes one self-contained HTML file
that opens offline in any current browser: every pose's target, its repairs and the reference under one camera,
intersecting faces (red: new, orange: the reference's own), the faces stretched or crushed beyond the summary's
distortion limit (a repair's against both the target and the reference, the target's against the reference), the
deviation heat map, ``V_C`` / free / pass-through regions (``posefix.report.viewer``).
"""

import json
from pathlib import Path

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

import numpy as np

from posefix.io.artifacts import read_artifact, read_repair
from posefix.io.errors import InputError
from posefix.io.files import atomic_write_bytes
from posefix.mesh.distortion import distorted_faces, distortion_summary
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.report.contents import SPACETIME, VIEWER_FILES
from posefix.report.tables import repair_names, entry_status
from posefix.report.viewer import mesh_record, page_data, pose_record, viewer_html
from posefix.spacetime.classification import split_frames
from posefix.workflow.cli import library_defaults, run_stage, stage_parser
from posefix.workflow.timings import Timings

PAGE = Path(posefix.report.viewer.__file__).parent
DISTORTION_LIMIT = library_defaults(distortion_summary)["limit"]
"""The distortion limit of an entry without one (a summary.json written before the distortion was measured)."""


def build_parser():
    return stage_parser("viewer", __doc__, summary="summary.json of the library (its poses and repairs)",
                        results="results/<library> folder (<pose>/*.h5)", out="viewer.html to write")


def read_summary(path):
    """The library's name and the entries of ``summary.json``; :class:`InputError` when it is none."""
    try:
        summary = json.loads(Path(path).read_text())
        return summary["library"], summary["poses"]
    except (ValueError, KeyError, TypeError) as exc:
        raise InputError(path, f"not a posefix summary.json ({exc})") from None


def read_pose(folder, names, reference):
    """One pose's artifacts: ``(target, repairs, keyframes, classify, verify, keyframes' attributes)``; the target
    ``(V, hit)``, the repairs ``{name: (V, hit)}`` (space-time first, then the other repairs ``names``; ``hit``:
    intersecting faces), keyframes with
    ``reference_hit`` (the reference's intersecting faces) added; its reference and faces checked against
    ``reference`` ``(V, F, ...)`` of the library (None: the first pose, which sets it)."""
    kf, attrs = read_artifact(folder / "keyframes.h5", "keyframes", ["reference", "target", "faces"])
    if reference is not None and not (np.array_equal(kf["reference"], reference[0])
                                      and np.array_equal(kf["faces"], reference[1])):
        raise InputError(folder / "keyframes.h5", "its reference or faces differ from the library's first pose's")
    cl, _ = read_artifact(folder / "classify.h5", "classify", ["mask", "pairs", "pair_offsets"])
    ve, _ = read_artifact(folder / "verify.h5", "verify", ["repaired", "deviation", "replaced", "pairs"])
    F, m = kf["faces"], len(kf["faces"])
    frames = split_frames(cl["pairs"], cl["pair_offsets"])
    repairs = {SPACETIME: (ve["repaired"], intersecting_faces(ve["pairs"], m))}
    for name in names:
        X = read_repair(folder / f"{name}.h5", name, ["repaired"])[0]["repaired"]
        if X.shape != kf["target"].shape:
            raise InputError(folder / f"{name}.h5", f"repaired {X.shape}, the pose has {kf['target'].shape}")
        repairs[name] = (X, intersecting_faces(self_intersecting_pairs(X, F), m))
    kf["reference_hit"] = intersecting_faces(frames[0], m)
    return (kf["target"], intersecting_faces(frames[-1], m)), repairs, kf, cl, ve, attrs


def main(args, log):
    timings = Timings()
    library, entries = read_summary(args.summary)
    if not entries:
        raise InputError(args.summary, "lists no pose")
    names, reference, bounds, poses = repair_names(entries), None, [], []
    for entry in entries:
        target, repairs, kf, cl, ve, attrs = read_pose(Path(args.results) / entry["pose"], names, reference)
        reference = (kf["reference"], kf["faces"], kf["reference_hit"], float(attrs["metrics"]["bbox_diagonal"]))
        shown = np.vstack([kf["reference"], target[0], *(X for X, _ in repairs.values())])
        bounds += [shown.min(axis=0), shown.max(axis=0)]
        hit, F = kf["reference_hit"], kf["faces"]
        limit = entry.get("distortion", {}).get("limit", DISTORTION_LIMIT)
        meshes = [mesh_record("target", *target, hit, ("reference", reference[0]),
                              distorted_faces(target[0], [kf["reference"]], F, limit))]
        meshes += [mesh_record(name, X, faces, hit, ("target", target[0]),
                               distorted_faces(X, [target[0], kf["reference"]], F, limit))
                   for name, (X, faces) in repairs.items()]
        poses.append(pose_record(entry["pose"], entry_status(entry), meshes, cl["mask"].astype(bool),
                                 ve["replaced"], ve["deviation"]))
        log.info("%s: %s", entry["pose"], ", ".join(f"{m['name']} {m['faces']} faces ({m['new']} new)" for m in meshes))
    V, F, hit, diagonal = reference
    with timings.step("page"):
        files = {key: (PAGE / path).read_text(encoding="utf-8") for key, path in VIEWER_FILES.items()}
        bounds = (np.min(bounds, axis=0), np.max(bounds, axis=0))  # of every mesh: the first view shows them all
        page = viewer_html(page_data(library, (V, hit), F, poses, diagonal, bounds, limit), files).encode()
        atomic_write_bytes(args.out, page)
    log.info("wrote %s (%d poses, %.1f MB)", args.out, len(poses), len(page) / 1e6)


if __name__ == "__main__":
    run_stage(build_parser(), main)
