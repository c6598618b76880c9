"""A pose job: the poses of one mesh repaired in memory (:func:`posefix.repair_pose`), from a folder that another
program wrote, in a process of its own. The Blender add-on (``blender/``) starts it so that Blender's interface stays
live, and reads its progress and results back:

    python -m posefix.workflow.pose_job FOLDER [--cores N]

``FOLDER/job.npz`` holds ``reference`` (n, 3), ``faces`` (m, 3), ``poses`` (k, n, 3) and ``names`` (k,); an optional
``FOLDER/settings.json`` the pipeline settings to change (``docs/api.md``). Each repaired pose goes to
``FOLDER/repaired-<i>.npy`` (n, 3) float64, in the order of ``names``, and stdout gets one JSON line per pose as it
finishes (:func:`pose_line`; a pose that could not be repaired: status ``error`` and its one-line reason, and the
others go on). ``FOLDER/results.json`` lists them all at the end. A job that cannot run is one line on stderr,
``posefix: error: ...``, and exit status 1 (2 for a bad command line). The poses are repaired on ``--cores``
spawned processes, which die with the job (:mod:`posefix.workflow.processes`).
"""

import argparse
import json
import sys
from pathlib import Path

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)
import numpy as np

from posefix.io.errors import PosefixError
from posefix.pose_repair import repair_pose
from posefix.workflow.processes import ordered_map


def pose_line(name, result):
    """The JSON-ready summary of one repaired pose (a :class:`posefix.pose_repair.PoseRepair`): its status and
    reason, intersecting faces of the target and the repair, new ones, and the faces beyond the distortion limit."""
    m = result.metrics
    return {"name": name, "status": result.status, "reason": result.reason,
            "intersecting_faces": {"target": int(m["intersecting_faces_target"]),
                                   "repaired": int(m["intersecting_faces_repaired"]),
                                   "repaired_new": int(m["repaired_new"])},
            "distorted_faces": int(m["distortion"]["faces_over"]),
            "deviation_free_max": float(m["deviation_free_max"])}


def run_job(folder, cores=1):
    """Repair the poses of the job in ``folder`` (module docstring) on ``cores`` processes: the list of
    :func:`pose_line` dicts, also written to ``results.json``; one JSON line per pose on stdout as it finishes."""
    folder = Path(folder)
    with np.load(folder / "job.npz") as job:
        reference, faces, poses, names = (job[k] for k in ("reference", "faces", "poses", "names"))
    settings_file = folder / "settings.json"
    settings = json.loads(settings_file.read_text()) if settings_file.is_file() else None
    jobs = [(reference, faces, pose, settings) for pose in poses]
    lines = []
    for i, result in enumerate(ordered_map(_repaired, jobs, cores)):
        if isinstance(result, str):  # this pose failed: the others go on
            lines.append({"name": str(names[i]), "status": "error", "reason": result})
        else:
            np.save(folder / f"repaired-{i}.npy", result.V)
            lines.append(pose_line(str(names[i]), result))
        print(json.dumps(lines[-1] | {"done": i + 1, "total": len(names)}), flush=True)
    (folder / "results.json").write_text(json.dumps(lines, indent=1))
    return lines


def _repaired(reference, faces, pose, settings):
    """:func:`posefix.repair_pose`'s result, or its one-line error (str, without the argument's name: the pose is
    named by the job)."""
    try:
        return repair_pose(reference, faces, pose, settings)
    except PosefixError as exc:
        return str(exc).removeprefix("V_target: ")


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m posefix.workflow.pose_job", description=__doc__.split("\n\n")[0])
    parser.add_argument("folder", help="the job's folder (job.npz, settings.json)")
    parser.add_argument("--cores", type=int, default=1, help="poses repaired at once (default 1)")
    args = parser.parse_args(argv)
    try:
        run_job(args.folder, max(1, args.cores))
    except (PosefixError, OSError, KeyError, ValueError) as exc:
        print(f"posefix: error: {exc}", file=sys.stderr, flush=True)
        sys.exit(1)


if __name__ == "__main__":
    main()
