"""The summary of a run in which some poses failed: the poses that finished, the others with their error line.

Snakemake runs the summary only when every pose has finished; after a failed run the workflow (``onerror`` in
``rules/report.smk``) writes it for the poses that did, with the failed ones listed apart (stage summary's
``--failed``), and the run still exits with an error.
"""

import json
import os
import re
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
    named = re.compile(rf"(^|[/\\\s]){re.escape(pose)}[./\\]")
    return next((line for line in lines if named.search(line)), "did not finish (see the log)")


def stage_finished(command):
    """Run the stage ``command`` (list of str: the interpreter, the stage's script, its arguments with ``--log
    <file>``) with its output discarded (its log keeps its lines): whether it finished. Where it did not, one line
    on stderr names the stage and its log, so that a failed run's partial summary never fails unsaid."""
    if subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode == 0:
        return True
    print(f"posefix: warning: {Path(command[1]).stem} of the poses that finished failed too (see "
          f"{command[command.index('--log') + 1]})", file=sys.stderr)
    return False
