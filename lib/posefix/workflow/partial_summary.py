"""The summary of a run in which some poses failed: the poses that finished, the others with their error line.

Snakemake runs the summary only when every pose has finished; after a failed run the workflow (``onerror`` in
``rules/report.smk``) writes it for the poses that did, with the failed ones listed apart (stage summary's
``--failed``), and the run still exits with an error.
"""

import re
import subprocess
import sys
from pathlib import Path


def finished_poses(required):
    """``(finished, unfinished)``: the poses (lists, in the given order) whose ``required`` files (dict: pose -> list
    of paths) all exist, and the others."""
    finished = [pose for pose, paths in required.items() if all(Path(p).is_file() for p in paths)]
    return finished, [pose for pose in required if pose not in finished]


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
