"""The posefix command: the workflow from any folder, the posefix error lines at the end of a failed run."""

import subprocess
import sys
from pathlib import Path

import pytest

from conftest import QUICK_DOWNSTREAM, icosphere
from posefix.workflow.command import WORKFLOW, build_parser, snakemake_command
from posefix.io.meshes import write_mesh


def posefix(*args, cwd):
    """``posefix ...`` (the venv's console script when installed, else the module) in ``cwd``."""
    script = Path(sys.executable).parent / "posefix"
    command = [str(script)] if script.exists() else [sys.executable, "-m", "posefix.workflow.command"]
    return subprocess.run([*command, *map(str, args)], capture_output=True, text=True, cwd=cwd, timeout=900)


def test_the_snakemake_command_line(tmp_path):
    args = build_parser().parse_args(["repair", str(tmp_path), "--cores", "4", "--profile", "slurm",
                                      "--config", "poses=a,b"])
    command = snakemake_command(args)
    assert command[1:5] == ["-m", "snakemake", "-s", str(WORKFLOW / "Snakefile")]
    assert command[5:8] == ["--config", f"library={tmp_path.resolve()}", "poses=a,b"]
    assert command[8:] == ["--cores", "4", "--workflow-profile", str(WORKFLOW / "profiles" / "slurm")]
    report = snakemake_command(build_parser().parse_args(["report", str(tmp_path)]))
    assert report[-2:] == ["--report", f"reports/{tmp_path.name}/report.html"]


@pytest.mark.pipeline
def test_posefix_repair_from_another_folder_matches_the_workflow_run(demo_run, tmp_path):
    proc = posefix("repair", demo_run / "data" / "demo", "--config", QUICK_DOWNSTREAM, "poses=demo-01",
                   cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "steps (100%) done" in proc.stdout and len(proc.stdout.splitlines()) < 200
    name = "results/demo/repaired/demo-01.obj"
    assert (tmp_path / name).read_bytes() == (demo_run / name).read_bytes()
    assert list((tmp_path / "posefix-logs").glob("repair-*.log"))
    proc = posefix("report", demo_run / "data" / "demo", "--config", QUICK_DOWNSTREAM, "poses=demo-01",
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
