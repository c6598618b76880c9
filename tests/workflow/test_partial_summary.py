"""The summary of a failed run: which poses finished, and the error line of each that did not."""

import sys
from types import SimpleNamespace

from posefix.workflow.partial_summary import finished_poses, partial_pack, partial_report, pose_errors, stage_finished


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


def _recording_stages(tmp_path):
    """A stage_script function whose every stage writes its arguments to <stage>.args (and exits 0)."""
    def stage_script(name):
        script = tmp_path / f"{name}.py"
        script.write_text(f"import sys, pathlib\npathlib.Path({str(tmp_path / name)!r} + '.args').write_text("
                          "'\\n'.join(sys.argv[1:]))\n")
        return str(script)
    return stage_script


def test_the_partial_report_runs_summary_overview_and_viewer_for_the_finished_poses_only(tmp_path, capsys):
    stages = _recording_stages(tmp_path)
    partial_report(stages, ("res/lib", "rep/lib"), (["a"], ["b"]), ["posefix fit: error: res/lib/b/fit.h5: bad"],
                   (["contact"], 4.0))
    summary = (tmp_path / "summary.args").read_text().splitlines()
    assert summary[summary.index("--poses") + 1] == "a" and "--failed=b=posefix fit: error: res/lib/b/fit.h5: bad" \
        in summary and summary[summary.index("--repairs") + 1] == "contact"
    assert (tmp_path / "overview.args").exists() and (tmp_path / "viewer.args").exists()
    assert capsys.readouterr().err.splitlines() == [
        "posefix: summary of the 1 poses that finished, 1 listed as failed: rep/lib/summary.html"]
    for poses in ((["a", "b"], []), ([], ["a", "b"])):  # all finished (the run's own summary), or none: nothing
        (tmp_path / "summary.args").unlink(missing_ok=True)
        partial_report(stages, ("res/lib", "rep/lib"), poses, [], ([], 4.0))
        assert not (tmp_path / "summary.args").exists()


def test_a_partial_pack_writes_the_repairs_file_with_the_poses_done(tmp_path, capsys):
    script = _recording_stages(tmp_path)("pack")
    library = SimpleNamespace(container="/data/walk.usdc", mesh="/Body")
    partial_pack(script, library, "res/lib/repaired-contact", ["a"], 2)
    args = (tmp_path / "pack.args").read_text().splitlines()
    assert args[args.index("--out") + 1] == "res/lib/repaired-contact/walk.usdc"
    assert args[args.index("--log") + 1] == "res/lib/logs/partial-pack-repaired-contact.log"
    assert capsys.readouterr().err.strip() == ("posefix: res/lib/repaired-contact/walk.usdc: 1 of 2 poses repaired, "
                                               "the others as in the input")
    (tmp_path / "pack.args").unlink()
    partial_pack(script, library, "res/lib/repaired", ["a", "b"], 2)
    assert not (tmp_path / "pack.args").exists()
