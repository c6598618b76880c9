"""The summary of a failed run: which poses finished, and the error line of each that did not."""

import sys

from posefix.workflow.partial_summary import finished_poses, pose_errors, stage_finished


def test_a_pose_finished_when_every_file_it_needs_exists(tmp_path):
    (tmp_path / "a.h5").write_text("")
    (tmp_path / "b.h5").write_text("")
    required = {"walk": [tmp_path / "a.h5", tmp_path / "b.h5"], "run": [tmp_path / "a.h5", tmp_path / "c.h5"],
                "jump": []}
    assert finished_poses(required) == (["walk", "jump"], ["run"])


def test_each_failed_pose_gets_the_first_error_line_that_names_its_file_or_folder():
    lines = ["posefix validate: error: /data/lib/walk.obj: line 4: face vertex index 9",
             "posefix fit: error: results/lib/walk-2/constraints.h5: too few",
             "posefix fit: error: results/lib/walk/constraints.h5: later"]
    assert pose_errors(["walk", "walk-2", "wal", "run"], lines) == {
        "walk": lines[0], "walk-2": lines[1], "wal": "did not finish (see the log)",
        "run": "did not finish (see the log)"}


def test_a_partial_summary_stage_that_fails_says_so_in_one_line_naming_its_log(tmp_path, capsys):
    """Its output is discarded (its log keeps it), so the line is all the user sees (issue 50)."""
    script = tmp_path / "overview.py"
    script.write_text("import sys\nprint('noise')\nsys.exit(1)\n")
    assert not stage_finished([sys.executable, str(script), "--log", "results/lib/logs/partial-overview.log"])
    assert capsys.readouterr().err.splitlines() == [
        "posefix: warning: overview of the poses that finished failed too (see results/lib/logs/partial-overview.log)"]
    script.write_text("print('noise')\n")
    assert stage_finished([sys.executable, str(script), "--log", "x.log"]) and capsys.readouterr().err == ""
