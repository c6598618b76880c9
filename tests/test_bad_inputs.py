"""The probe of bad inputs (tests/bad_inputs.py): each gives its one line, exits with an error, and a bad pose file
leaves the library's good poses repaired; docs/errors.md lists them all."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from bad_inputs import CASES, FILES, markdown
from conftest import ROOT
from posefix.io.meshes import write_mesh
from posefix.workflow.demo import demo_library

pytestmark = pytest.mark.pipeline

POSES = ("demo-01", "demo-02")


def posefix(args, cwd, env=None):
    """``posefix <args>`` (the venv's console script) in ``cwd``."""
    script = Path(sys.executable).parent / "posefix"
    command = [str(script)] if script.exists() else [sys.executable, "-m", "posefix.workflow.command"]
    return subprocess.run([*command, *args], capture_output=True, text=True, cwd=cwd, env=env, timeout=900)


def limb(run):
    """The demo limb at 362 vertices, its reference and :data:`POSES`, in ``run``/lib: the folder."""
    V, F, poses = demo_library(around=12)
    lib = run / "lib"
    write_mesh(lib / "reference.obj", V, F)
    for name in POSES:
        write_mesh(lib / f"{name}.obj", poses[name], F)
    return lib


def _gpu_present():
    from posefix.spacetime.integration_opencl import select_device
    return select_device("gpu")[0] is not None


@pytest.mark.parametrize("case", [c for c in CASES if c.kind != "file"], ids=lambda c: f"{c.kind}: {c.what}")
def test_a_bad_input_gives_its_one_line_and_an_error_exit(case, tmp_path):
    if "device=gpu" in " ".join(case.args) and _gpu_present():
        pytest.skip("this machine has a GPU OpenCL device: a run on it is no bad input")
    lib = limb(tmp_path)
    if case.make:
        case.make(lib)
    fill = lambda text: text.replace("{lib}", str(lib)).replace("{run}", str(tmp_path))  # noqa: E731
    env = os.environ | {k: fill(v) for k, v in case.env.items() if k != "CWD"}
    proc = posefix([fill(a) for a in case.args], case.env.get("CWD", tmp_path), env)
    said = [line for line in proc.stderr.splitlines() if not line.startswith("posefix: Snakemake's full output: ")]
    assert proc.returncode != 0 and said == [fill(case.line)], proc.stderr


def test_bad_pose_files_each_give_their_one_line_and_the_good_poses_are_repaired(tmp_path):
    """Every file case in one library beside the good poses: one run."""
    lib = limb(tmp_path)
    for case in FILES:
        case.make(lib)
    proc = posefix(["repair", str(lib), "--config", "repairs=[]"], tmp_path)
    lines = (proc.stdout + proc.stderr).splitlines()
    assert proc.returncode == 1 and "Traceback" not in proc.stderr, proc.stderr[-3000:]
    for case in FILES:
        line = case.line.replace("{lib}", str(lib))
        assert lines.count(line) == 1, (line, proc.stdout[-3000:], proc.stderr[-3000:])
    summary = json.loads((tmp_path / "reports" / "lib" / "summary.json").read_text())
    assert [e["pose"] for e in summary["poses"]] == list(POSES)
    assert all((tmp_path / "results" / "lib" / "repaired" / f"{p}.obj").is_file() for p in POSES)


def test_docs_errors_md_lists_every_case():
    assert (ROOT / "docs" / "errors.md").read_text() == markdown(), \
        "docs/errors.md is stale: python tests/bad_inputs.py > docs/errors.md"
