"""The summary of a run in which some poses failed: the poses that finished, the others with their error line.

Snakemake runs the summary only when every pose has finished; after a failed run the workflow (``onerror`` in
``rules/report.smk``) writes it for the poses that did, with the failed ones listed apart (stage summary's
``--failed``), and the run still exits with an error.
"""

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

NESTED = "POSEFIX_STALE_CHECK"
"""Set in the environment of :func:`stale_files`' own Snakemake run: the workflow parsed there checks no staleness
itself (it would start another)."""


def finished_poses(required, stale=frozenset()):
    """``(finished, unfinished)``: the poses (lists, in the given order) whose ``required`` files (dict: pose -> list
    of paths) all exist and none of which is ``stale`` (:func:`stale_files`), and the others."""
    finished = [pose for pose, paths in required.items()
                if all(Path(p).is_file() and str(p) not in stale for p in paths)]
    return finished, [pose for pose in required if pose not in finished]


def stale_files(snakefile, config, files):
    """Of ``files`` (list of str: outputs of the workflow, relative to the working folder), those that exist but that
    this code and these inputs would make again: Snakemake's own rerun triggers (changed code, parameters, input
    files), from the ``--summary`` table of a run of ``snakefile`` with ``config`` (dict: the whole config), set of
    str. A file made by an earlier run and out of date since (its pose changed, and failed now) is never taken as
    this run's. Empty where the check itself is nested in one (:data:`NESTED`) or cannot run."""
    existing = [str(f) for f in files if Path(f).is_file()]
    if os.environ.get(NESTED) or not existing:
        return set()
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as handle:
        json.dump(config, handle)
    try:
        proc = subprocess.run([sys.executable, "-m", "snakemake", "-s", str(snakefile), "--configfile", handle.name,
                               "--summary", "--nolock", *existing], capture_output=True, text=True,
                              env=os.environ | {NESTED: "1"})
    finally:
        os.unlink(handle.name)
    if proc.returncode != 0:
        print(f"posefix: warning: could not tell which earlier results are out of date (taken as they are): "
              f"{proc.stderr.strip().splitlines()[-1:] or proc.returncode}", file=sys.stderr)
        return set()
    return planned_updates(proc.stdout)


def planned_updates(table):
    r"""The files that Snakemake's ``--summary`` ``table`` (str, tab-separated, a header line first) plans to make
    again (its last column is not "no update"), set of str.

    Examples
    --------
    >>> planned_updates("output_file\tdate\trule\tlog-file(s)\tstatus\tplan\n"
    ...                 "r/a/verify.h5\tMon\tverify\tr/a.log\tparams changed\tupdate pending\n"
    ...                 "r/b/verify.h5\tMon\tverify\tr/b.log\tok\tno update\n")
    {'r/a/verify.h5'}
    """
    rows = [line.split("\t") for line in table.splitlines()]
    start = next((i + 1 for i, row in enumerate(rows) if row[:1] == ["output_file"]), len(rows))
    return {row[0] for row in rows[start:] if len(row) >= 6 and row[5] != "no update"}


def pose_errors(poses, error_lines):
    """``{pose: its error line}`` for ``poses``: the first of ``error_lines`` that names the pose's file or results
    folder (``.../<pose>.obj``, ``.../<pose>/...``), else that it did not finish.

    Examples
    --------
    >>> pose_errors(["walk-2", "run"], ["posefix fit: error: results/lib/walk-2/constraints.h5: too few"])
    {'walk-2': 'posefix fit: error: results/lib/walk-2/constraints.h5: too few', 'run': 'did not finish (see the log)'}
    """
    return {pose: _first_naming(pose, error_lines) for pose in poses}


def _first_naming(pose, lines):
    """The first of ``lines`` that names the file or results folder of ``pose``, else that it did not finish."""
    return next((line for line in lines if _names(line, pose)), "did not finish (see the log)")


def _names(line, pose):
    """Whether ``line`` (str) names ``pose`` as a file or folder: after its start, a slash or a space, before a dot or
    a slash."""
    start = line.find(pose)
    while start >= 0:
        after = line[start + len(pose):start + len(pose) + 1]
        if (start == 0 or line[start - 1] in "/\\" or line[start - 1].isspace()) and after and after in "./\\":
            return True
        start = line.find(pose, start + 1)
    return False


def stage_finished(command):
    """Run the stage ``command`` (list of str: the interpreter, the stage's script, its arguments with ``--log
    <file>``) with its output discarded (its log keeps its lines): whether it finished. Where it did not, one line
    on stderr names the stage and its log, so that a failed run's partial summary never fails unsaid."""
    if subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode == 0:
        return True
    print(f"posefix: warning: {Path(command[1]).stem} of the poses that finished failed too (see "
          f"{command[command.index('--log') + 1]})", file=sys.stderr)
    return False


def partial_report(stage_script, folders, poses, errors, options):
    """After a failed run: run the summary, overview and 3D viewer stages for the poses that finished, the others
    listed with their error line; nothing when no pose or every pose finished.

    Parameters
    ----------
    stage_script : callable
        Stage name -> path of its script (``stages/<name>.py``).
    folders : tuple of str
        (results/<library>, reports/<library>).
    poses : tuple of list
        (finished, unfinished) pose names (:func:`finished_poses`).
    errors : list of str
        The posefix error lines of the failed jobs (:func:`pose_errors`).
    options : tuple
        (the repairs beside space-time (list of str), config ``summary.distortion_limit``).
    """
    (results, reports), (finished, unfinished), (repairs, limit) = folders, poses, options
    if not finished or not unfinished:
        return
    failed = [f"--failed={pose}={line}" for pose, line in pose_errors(unfinished, errors).items()]
    logs = f"{results}/logs"
    commands = [
        [sys.executable, stage_script("summary"), "--results", results, "--poses", ",".join(finished),
         "--repairs", ",".join(repairs), "--distortion-limit", str(limit), *failed, "--out",
         f"{reports}/summary.json", "--markdown", f"{reports}/summary.md", "--log", f"{logs}/partial-summary.log"],
        [sys.executable, stage_script("overview"), "--summary", f"{reports}/summary.json", "--png",
         f"{reports}/overview.png", "--html", f"{reports}/summary.html", "--log", f"{logs}/partial-overview.log"],
        [sys.executable, stage_script("viewer"), "--summary", f"{reports}/summary.json", "--results", results,
         "--out", f"{reports}/viewer.html", "--log", f"{logs}/partial-viewer.log"],
    ]
    if all(stage_finished(command) for command in commands):
        print(f"posefix: summary of the {len(finished)} poses that finished, {len(unfinished)} listed as failed: "
              f"{reports}/summary.html", file=sys.stderr)


def partial_pack(script, library, folder, done, total):
    """After a failed run of a container library: write the file of one repair (stage pack, its ``script``) with the
    poses ``done`` (list of str) repaired and the others as in the input, so that one bad pose does not hold back
    the others; nothing when none or all ``total`` poses are done. ``folder``: the repair's folder of meshes
    (results/<library>/repaired[-<repair>]); ``library``: the posefix.io.library.Library."""
    if not done or len(done) == total:
        return
    out = f"{folder}/{os.path.basename(library.container)}"
    command = [sys.executable, script, "--container", library.container, "--mesh", library.mesh, "--repaired",
               folder, "--poses", ",".join(done), "--out", out,
               "--log", f"{os.path.dirname(folder)}/logs/partial-pack-{os.path.basename(folder)}.log"]
    if stage_finished(command):
        print(f"posefix: {out}: {len(done)} of {total} poses repaired, the others as in the input", file=sys.stderr)
