"""The posefix command: the workflow from any folder, the posefix error lines at the end of a failed run."""

import argparse
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from conftest import h5_datasets, icosphere
from posefix.workflow.command import WORKFLOW, build_parser, print_missed_errors, shown, snakemake_command
from posefix.workflow.events import failed_job_errors, failure_line, recap_line
from posefix.io.errors import InputError
from posefix.io.meshes import read_mesh, write_mesh


def posefix(*args, cwd):
    """``posefix ...`` (the venv's console script when installed, else the module) in ``cwd``."""
    script = Path(sys.executable).parent / "posefix"
    command = [str(script)] if script.exists() else [sys.executable, "-m", "posefix.workflow.command"]
    return subprocess.run([*command, *map(str, args)], capture_output=True, text=True, cwd=cwd, timeout=900)


def ball_library(library):
    """A library folder of a sphere and one pose of it, scaled: the folder."""
    V, F = icosphere(2)
    write_mesh(library / "ball-reference.obj", V, F)
    write_mesh(library / "ball-01.obj", V * 1.1, F)
    return library


def test_help_says_each_default_once_and_in_words():
    assert "``" not in build_parser().format_help()
    from posefix.workflow.cli import stage_parser
    parser = stage_parser("x", "")
    parser.add_argument("--out", required=True, help="where")
    parser.add_argument("--align", action=argparse.BooleanOptionalAction, default=True, help="align")
    parser.add_argument("--poses", default=None, help="poses (default: all)")
    parser.add_argument("--ring", type=int, default=0, help="rings")
    text = " ".join(parser.format_help().split())
    assert "--out OUT where --align" in text and "align (on by default)" in text
    assert "poses (default: all) --ring" in text and "rings (default: 0)" in text


def test_the_snakemake_command_line(tmp_path):
    args = build_parser().parse_args(["repair", str(tmp_path), "--cores", "4", "--profile", "slurm",
                                      "--config", "poses=a,b"])
    command = snakemake_command(args)
    assert command[1:5] == ["-m", "snakemake", "-s", str(WORKFLOW / "Snakefile")]
    assert command[5:8] == ["--config", f"library={tmp_path.resolve()}", "poses=a,b"]
    assert command[8:] == ["--cores", "4", "--workflow-profile", str(WORKFLOW / "profiles" / "slurm")]
    report = snakemake_command(build_parser().parse_args(["repair", str(tmp_path), "--memory", "7.5"]))
    assert report[-4:] == ["--cores", "2", "--resources", "mem_mb=7500"]
    report = snakemake_command(build_parser().parse_args(["report", str(tmp_path)]))
    assert report[-2:] == ["--report", f"reports/{tmp_path.name}/report.html"]


@pytest.mark.pipeline
def test_a_library_too_large_for_the_memory_given_is_refused_in_one_line_before_anything_runs(tmp_path):
    library = ball_library(tmp_path / "lib")
    proc = posefix("repair", library, "--memory", "0.2", cwd=tmp_path)
    assert proc.returncode != 0 and "Traceback" not in proc.stderr, proc.stderr
    lines = proc.stderr.splitlines()
    assert lines[0].startswith(f"posefix: error: {library / 'ball-reference.obj'}: 162 vertices need about 1.0 GB "
                               "in stage ") and "more than the 0.2 GB this run may use" in lines[0], lines
    assert len(lines) == 2 and not (tmp_path / "results").exists()


@pytest.mark.pipeline
def test_posefix_repair_from_another_folder_matches_the_workflow_run(demo_run, tmp_path):
    proc = posefix("repair", demo_run / "data" / "demo", "--config", "poses=demo-01", "repairs=[]",
                   cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    lines = proc.stdout.splitlines()
    assert lines[0].startswith("posefix: ") and lines[0].endswith(" jobs to run") and len(lines) < 20, lines
    assert any(line.endswith(" jobs done (100%)") for line in lines), lines
    assert lines[-5].startswith("posefix: 1 poses repaired: ") and lines[-4].startswith("  demo-01: "), lines
    assert lines[-3:] == ["posefix: repaired meshes: results/demo/repaired",
                          "posefix: summary page: reports/demo/summary.html",
                          "posefix: 3D viewer: reports/demo/viewer.html"], lines
    name = "results/demo/repaired/demo-01.obj"
    assert (tmp_path / name).read_bytes() == (demo_run / name).read_bytes()
    for stage in ("keyframes", "classify", "fit", "verify"):  # deterministic: the same numbers
        a, b = (h5_datasets(run / "results" / "demo" / "demo-01" / f"{stage}.h5") for run in (demo_run, tmp_path))
        assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a if "seconds" not in k), stage
    assert not (tmp_path / "results" / "demo" / "demo-02").exists()
    assert list((tmp_path / "posefix-logs").glob("repair-*.log"))
    proc = posefix("report", demo_run / "data" / "demo", "--config", "poses=demo-01", "repairs=[]",
                   cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert (tmp_path / "reports" / "demo" / "report.html").stat().st_size > 100_000


@pytest.mark.pipeline
def test_a_failed_run_ends_with_the_posefix_error_line(tmp_path):
    library = tmp_path / "lib"
    V, F = icosphere(1)
    write_mesh(library / "ball-reference.obj", V, F)
    (library / "ball-01.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    proc = posefix("repair", library, cwd=tmp_path)
    assert proc.returncode != 0 and "Traceback" not in proc.stderr
    lines = proc.stderr.splitlines()
    assert lines[0].startswith("posefix validate: error:") and "ball-01.obj: line 4: face vertex index 9" in lines[0]
    assert lines[-1].startswith("posefix: Snakemake's full output: posefix-logs/repair-") and len(lines) == 2
    assert "error:" not in proc.stdout  # once, on stderr


@pytest.mark.pipeline
def test_a_second_run_in_a_folder_where_one_works_is_refused_in_one_line(tmp_path):
    """While a repair works in a folder, a second one started there stops at once with one line (no traceback), and
    leaves the first one's work alone."""
    library = ball_library(tmp_path / "lib")
    first = subprocess.Popen([sys.executable, "-m", "posefix.workflow.command", "repair", str(library), "--config",
                              "repairs=[]"], cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                             start_new_session=True)
    try:
        for _ in range(600):  # until Snakemake has locked the folder
            if any((tmp_path / ".snakemake" / "locks").glob("*.lock")) or first.poll() is not None:
                break
            time.sleep(0.1)
        assert first.poll() is None, "the first run ended before the second started"
        proc = posefix("repair", library, "--config", "repairs=[]", cwd=tmp_path)
    finally:
        os.killpg(first.pid, signal.SIGINT)
        first.wait(timeout=120)
    assert proc.returncode != 0 and "Traceback" not in proc.stderr, proc.stderr
    lines = proc.stderr.splitlines()
    assert lines[0] == (f"posefix: error: {tmp_path}: another Snakemake run is working in this folder; wait for it to "
                        "finish (if none is running: snakemake --unlock)"), lines
    assert len(lines) == 2 and lines[1].startswith("posefix: Snakemake's full output: posefix-logs/repair-")


@pytest.mark.parametrize("args, line", [
    (["--cores", "0"], "posefix: error: --cores 0: needs at least 1 core"),
    (["--cores", "-1"], "posefix: error: --cores -1: needs at least 1 core"),
    (["--memory", "0"], "posefix: error: --memory 0: needs more than 0 GB"),
    (["--profile", "slrum"], "posefix: error: --profile slrum: no such profile (shipped: default, slurm; or give a "
                             "folder)"),
])
def test_arguments_that_cannot_be_right_are_refused_in_one_line_before_anything_runs(tmp_path, args, line):
    proc = posefix("repair", tmp_path, *args, cwd=tmp_path)
    assert proc.returncode != 0 and proc.stderr.splitlines() == [line] and proc.stdout == ""
    assert not (tmp_path / "posefix-logs").exists() and not (tmp_path / ".snakemake").exists()


def test_a_library_named_after_config_is_refused_in_one_line_that_says_where_it_goes(tmp_path):
    """``--config`` takes every word after it, so a library after it was taken for a setting (issue 50: the run
    ended in ``ValueError: not enough values to unpack``)."""
    proc = posefix("repair", "--config", "poses=a", tmp_path, cwd=tmp_path)
    assert proc.returncode != 0 and proc.stdout == "" and proc.stderr.splitlines() == [
        f"posefix: error: --config {tmp_path}: not KEY=VALUE (name the library before --config: posefix repair "
        "<library> --config KEY=VALUE ...)"]
    assert not (tmp_path / "posefix-logs").exists()


def test_a_usd_or_gltf_file_is_a_library_named_after_the_file(tmp_path):
    from posefix.workflow.command import argument_problem, finished_lines, library_name
    args = build_parser().parse_args(["report", str(tmp_path / "walk.cycle.usdz")])
    assert library_name(args) == "walk.cycle"
    assert argument_problem(args) == f"{tmp_path / 'walk.cycle.usdz'}: no such file"
    args = build_parser().parse_args(["repair", str(tmp_path / "walk.fbx")])
    assert argument_problem(args) == (f"{tmp_path / 'walk.fbx'}: not a folder, nor a USD, glTF or Alembic file (.usd, "
                                      ".usda, .usdc, .usdz, .gltf, .glb, .abc)")
    (tmp_path / "reports").mkdir()
    (tmp_path / "reports" / "summary.json").write_text('{"poses": []}')
    (tmp_path / "repaired").mkdir()
    (tmp_path / "repaired" / "walk.glb").write_bytes(b"glTF")
    assert finished_lines(tmp_path / "reports", tmp_path, container="walk.glb")[-2:] == [
        f"posefix: repaired meshes: {tmp_path / 'repaired'}",
        f"posefix: repaired file: {tmp_path / 'repaired' / 'walk.glb'}"]


def test_the_report_of_a_library_repaired_under_another_name_goes_to_that_name(tmp_path):
    report = snakemake_command(build_parser().parse_args(["report", str(tmp_path), "--config", "name=walk-2"]))
    assert report[-2:] == ["--report", "reports/walk-2/report.html"]


@pytest.mark.parametrize("events, text, line", [
    # posefix report before a repair: the explanation is on the line after "WorkflowError:" (issue 50)
    ([{"event": "error", "exception": "WorkflowError", "msg": "WorkflowError:\n\nFile reports/lib/figures/ball-01/"
                                                              "renders.png marked for report but does not exist.\n"}],
     [], "posefix: error: WorkflowError: File reports/lib/figures/ball-01/renders.png marked for report but does not "
         "exist."),
    ([{"event": "error", "exception": "NotADirectoryError", "msg": 'NotADirectoryError in file "Snakefile", line 37:\n'
                                                                   "[Errno 20] Not a directory: 'r/a'\n  File \"x\""}],
     [], "posefix: error: NotADirectoryError: [Errno 20] Not a directory: 'r/a'"),
    # the failed jobs' own error (a rule's exception) and the run's end are no cause in themselves
    ([{"event": "error", "exception": "RuleException", "msg": "RuleException:\nCalledProcessError in file x"},
      {"event": "error", "exception": "WorkflowError", "msg": "WorkflowError:\nAt least one job did not complete "
                                                              "successfully."}],
     [], "posefix: error: the run failed before any stage reported (see Snakemake's full output below)"),
    # before Snakemake's logger starts: its text
    ([], ["Using profile nope for setting default command line arguments.",
          "Error: profile directory given (nope), but no profile.yaml (or config.yaml) found. Profile has to be given"],
     "posefix: error: Snakemake: profile directory given (nope), but no profile.yaml (or config.yaml) found (a "
     "--profile or SNAKEMAKE_PROFILE that names no profile)"),
])
def test_a_run_that_fails_before_any_stage_reports_says_why_in_one_line(events, text, line):
    assert failure_line(events, "/work/here", text) == line


def test_the_output_lines_shown_as_they_are():
    assert shown("posefix: 3 of 9 jobs done\n") and shown("Nothing to be done (all requested files are present)")
    assert shown("11:02:39 posefix fit: warning: 3 constraint points dropped\n")
    assert not shown("11:02:39 posefix fit: read: 0.177 s\n") and not shown("Building DAG of jobs...\n")


@pytest.mark.pipeline
def test_a_dry_run_shows_the_jobs_it_would_run(tmp_path):
    library = ball_library(tmp_path / "lib")
    proc = posefix("repair", library, "-n", "--config", "repairs=[]", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    lines = proc.stdout.splitlines()
    assert lines[0] == "Job stats:" and any(line.split() == ["verify", "1"] for line in lines)
    assert lines[-1] == "This was a dry-run (flag -n). The order of jobs does not reflect the order of execution."
    assert not (tmp_path / "results" / "lib" / "ball-01").exists()


def job_error(rule, log):
    """Snakemake's event for a failed job whose log is ``log``."""
    return {"event": "job_error", "jobid": 1, "rule_name": rule, "log": [log]}


LOCKED = [{"event": "error", "exception": "LockException", "msg": "LockException:\nError: Directory cannot be locked."}]


def test_the_failed_jobs_error_lines_come_from_the_logs_snakemake_names(tmp_path):
    (tmp_path / "logs").mkdir()
    (tmp_path / "logs" / "fit.log").write_text("19:00:00 posefix fit: read\nTraceback...\n"
                                               "posefix fit: error: results/a/constraints.h5: too few\n")
    (tmp_path / "logs" / "validate.log").write_text("posefix validate: error: lib/b.obj: line 4\n")
    events = [job_error("fit", "logs/fit.log"), job_error("validate", "logs/validate.log"),
              job_error("fit", "logs/fit.log"), job_error("x", "logs/missing.log")]
    assert failed_job_errors(events, tmp_path) == ["posefix fit: error: results/a/constraints.h5: too few",
                                                   "posefix validate: error: lib/b.obj: line 4"]
    assert failed_job_errors(LOCKED, tmp_path) == [failure_line(LOCKED, tmp_path)]


def test_a_jobs_error_line_that_the_output_did_not_show_is_printed_from_its_log(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "logs").mkdir()
    (tmp_path / "logs" / "unpack.log").write_text("posefix unpack: error: ball.usda: frame 2: NaN\n")
    events = [job_error("unpack", "logs/unpack.log")]
    print_missed_errors(["posefix: 3 of 9 jobs doposefix unpack: error: ball.usd\n"], events, [])  # a broken line
    assert capsys.readouterr().err.splitlines() == ["posefix unpack: error: ball.usda: frame 2: NaN"]
    print_missed_errors(["posefix unpack: error: ball.usda: frame 2: NaN\n"], events, [])  # shown: not again
    assert capsys.readouterr().err == ""
    print_missed_errors([], LOCKED, [])  # no job's line: the run's
    assert capsys.readouterr().err.splitlines() == [failure_line(LOCKED, tmp_path)]
    print_missed_errors([], [], ["Error: profile directory given (x), but no profile.yaml (or config.yaml) found."])
    assert "profile directory given (x)" in capsys.readouterr().err
    print_missed_errors(["posefix validate: error: lib/b.obj: line 4\n"], LOCKED, [])
    assert capsys.readouterr().err == ""


def test_the_recap_of_a_failed_job_does_not_repeat_its_error_line():
    assert recap_line("posefix validate: error: lib/b.obj: line 4") == "posefix: failed in validate: lib/b.obj: line 4"
    assert recap_line("posefix: error: the run failed") == "posefix: error: the run failed"


def test_the_report_covers_the_poses_of_the_librarys_summary_unless_told(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    library = tmp_path / "walks"
    library.mkdir()
    args = build_parser().parse_args(["report", str(library)])
    assert "poses=" not in " ".join(snakemake_command(args))  # no summary yet: as given
    (tmp_path / "reports" / "walks").mkdir(parents=True)
    (tmp_path / "reports" / "walks" / "summary.json").write_text('{"library": "walks", "poses": [{"pose": "a"}, '
                                                                 '{"pose": "c"}]}')
    assert snakemake_command(args)[-3:] == ["poses=a,c", "--report", "reports/walks/report.html"]
    told = build_parser().parse_args(["report", str(library), "--config", "poses=b"])
    assert [e for e in snakemake_command(told) if e.startswith("poses=")] == ["poses=b"]


@pytest.mark.pipeline
def test_posefix_repair_of_a_usd_file_with_a_bad_frame_repairs_the_others_and_writes_the_file(tmp_path):
    """Issue 31: a library in one USD file through `posefix repair`; a NaN frame fails its pose in one line naming
    the file and the frame, the other frames are repaired and written back into the file (the bad one as it was)."""
    from containers import write_usd_frames
    from posefix.io.containers import open_container
    V, F = icosphere(2)
    V = V * (1 + 0.1 * np.sin(3 * V[:, 0]) * np.cos(2 * V[:, 1]))[:, None]  # not a quadric: the fit needs that
    bad = V * 1.2
    bad[7] = np.nan
    path = write_usd_frames(tmp_path / "ball.usda", V, [V * 1.1, bad, V * 0.9 + 0.05], F)
    proc = posefix("repair", path, "--config", "repairs=[]", cwd=tmp_path)
    assert proc.returncode != 0 and "Traceback" not in proc.stderr
    lines = (proc.stdout + proc.stderr).splitlines()
    assert f"posefix unpack: error: {path}: mesh /Character/Body, frame 2: 1 points are NaN or infinite (first: " \
           "point 7)" in lines, "\n".join(lines)  # in full, not cut
    written = tmp_path / "results" / "ball" / "repaired" / "ball.usda"
    assert "posefix: results/ball/repaired/ball.usda: 2 of 3 poses repaired, the others as in the input" in lines
    back, source = open_container(written), open_container(path)
    assert list(back.members) == ["ball-reference", "ball-1", "ball-2", "ball-3"]
    for pose in ("ball-1", "ball-3"):
        repaired = read_mesh(tmp_path / "results" / "ball" / "repaired" / f"{pose}.ply")[0]
        assert np.array_equal(back.points(pose), repaired.astype(np.float32).astype(np.float64))
    with pytest.raises(InputError, match="frame 2: 1 points are NaN"):
        back.points("ball-2")
    assert np.array_equal(back.points("ball-reference"), source.points("ball-reference"))
