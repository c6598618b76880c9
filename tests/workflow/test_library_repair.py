"""posefix.repair_library (issue 49, item 2): the workflow run in this process gives the command's repaired meshes
byte for byte, and bad arguments are refused with one ``PosefixError`` line; ``docs/api.md``'s examples (both
functions) run as written."""

import subprocess
import sys

import pytest

import posefix
from conftest import ROOT


@pytest.mark.pipeline
def test_the_documented_examples_run_and_the_library_repair_equals_the_commands(demo_run, tmp_path):
    """docs/api.md as a doctest, in an empty folder: its repair_library example repairs demo-01 (space-time, one
    downstream step), whose mesh is the session's demo run's byte for byte (plain snakemake; posefix repair gives
    the same: tests/workflow/test_wheel.py)."""
    proc = subprocess.run([sys.executable, "-m", "doctest", ROOT / "docs" / "api.md"], capture_output=True,
                          text=True, cwd=tmp_path, timeout=900)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    mesh = "results/demo/repaired/demo-01.obj"
    assert (tmp_path / "demo-run" / mesh).read_bytes() == (demo_run / mesh).read_bytes()
    logs = list((tmp_path / "demo-run" / "posefix-logs").glob("api-*.log"))
    assert len(logs) == 1 and "1 of " in logs[0].read_text()  # Snakemake's output went to the log


@pytest.mark.parametrize("arguments, line", [
    ({"repairs": ("space-time", "elastic")},
     "repairs: 'elastic' is not a repair (one of space-time, medial, volumetric, contact)"),
    ({"cores": 0}, "cores=0: needs at least 1 core"),
    ({"config": {"verify.finsh": "snap"}}, "config: verify.finsh: unknown key (did you mean 'finish'?)"),
])
def test_repair_library_refuses_bad_arguments_in_one_line(tmp_path, arguments, line):
    with pytest.raises(posefix.PosefixError) as caught:
        posefix.repair_library(out=tmp_path, **arguments)
    assert str(caught.value) == line
