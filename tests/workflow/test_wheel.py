"""The installable package (issue 49): a wheel built from this checkout carries the workflow (posefix/_workflow/),
and installed into a fresh virtual environment outside the checkout it repairs from an empty folder, byte for byte
as the checkout does."""

import os
import subprocess
import sys
import sysconfig

import pytest

from conftest import ROOT
from containers import write_usd_frames
from posefix.workflow.demo import demo_library
from posefix.workflow.files import PACKAGED, WORKFLOW_FILES

pytestmark = pytest.mark.pipeline


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """A virtual environment with the wheel of this checkout installed (its dependencies: this interpreter's, read
    through a .pth file, so that nothing is downloaded but the build backend): its bin folder."""
    tmp = tmp_path_factory.mktemp("wheel")
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "-w", tmp / "dist", ROOT],
                           capture_output=True, text=True, cwd=tmp)
    assert built.returncode == 0, built.stderr[-3000:]
    wheel, = (tmp / "dist").glob("posefix-*.whl")
    subprocess.run([sys.executable, "-m", "venv", tmp / "venv"], check=True, env=_outside_the_checkout())
    python = tmp / "venv" / "bin" / "python"
    site = subprocess.run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          capture_output=True, text=True, check=True).stdout.strip()
    (tmp / site / "posefix-dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    # --ignore-installed: the checkout's editable posefix, seen through the .pth file, is left alone
    proc = subprocess.run([python, "-m", "pip", "install", "--quiet", "--no-deps", "--no-index", "--ignore-installed",
                           wheel], capture_output=True, text=True, env=_outside_the_checkout())
    assert proc.returncode == 0, proc.stderr[-3000:]
    return tmp / "venv" / "bin"


def _outside_the_checkout():
    """This environment without PYTHONPATH: nothing of the checkout on the path."""
    return {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}


def _run(bin_folder, args, cwd):
    env = _outside_the_checkout()
    env["PATH"] = f"{bin_folder}{os.pathsep}{env['PATH']}"
    return subprocess.run([bin_folder / "posefix", *map(str, args)], capture_output=True, text=True, cwd=cwd,
                          env=env, timeout=900)


def test_the_wheel_carries_the_workflow_and_says_its_version(installed, tmp_path):
    from posefix import __version__
    proc = _run(installed, ["--version"], tmp_path)
    assert proc.returncode == 0 and proc.stdout.strip() == f"posefix {__version__}", proc.stderr
    where = subprocess.run([installed / "python", "-c", "from posefix.workflow.files import workflow_folder; "
                            "print(workflow_folder())"], capture_output=True, text=True, cwd=tmp_path,
                           env=_outside_the_checkout())
    folder = where.stdout.strip()
    assert folder.endswith(f"site-packages/posefix/{PACKAGED}") and str(ROOT) not in folder, where.stderr
    assert all(os.path.exists(os.path.join(folder, name)) for name in WORKFLOW_FILES)


def test_the_installed_command_repairs_the_demo_from_an_empty_folder_as_the_checkout_does(installed, demo_run,
                                                                                          tmp_path):
    proc = _run(installed, ["repair", "--config", "poses=demo-01", "repairs=[]", "downstream.max_iters=1"],
                tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    log = next((tmp_path / "posefix-logs").glob("*.log")).read_text()
    assert f"site-packages/posefix/{PACKAGED}/Snakefile" in log and str(ROOT / "Snakefile") not in log
    name = "results/demo/repaired/demo-01.obj"
    assert (tmp_path / name).read_bytes() == (demo_run / name).read_bytes()


def test_the_installed_command_reads_a_usd_library(installed, tmp_path):
    """A dry run on a USD file of two poses of the demo limb: the container's rules parse from the wheel's
    workflow, one unpack job per pose and the reference."""
    V, F, poses = demo_library(around=12)
    path = write_usd_frames(tmp_path / "limb.usda", V, [poses["demo-01"], poses["demo-02"]], F)
    proc = _run(installed, ["repair", path, "--dry-run", "--config", "repairs=[]"], tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "unpack" in proc.stdout + proc.stderr, proc.stdout[-3000:]
