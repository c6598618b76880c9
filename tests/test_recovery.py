"""Recovery and incremental reruns: a hard kill, an added pose, a bad pose, upgraded code, config mistakes.

Each test runs the workflow of a copy of this checkout (so the code-change test can edit its library
modules) on a small library of spheres in its own temporary folder.
"""

import os
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from conftest import ROOT, icosphere, split_along_a_seam
from posefix.io.meshes import write_mesh

pytestmark = pytest.mark.pipeline

SHAPES = {"ball-01": [1.2, 1.0, 1.0], "ball-02": [1.0, 1.2, 1.0], "ball-03": [1.0, 1.0, 1.2], "ball-04": [1.1, 1.1, 0.9]}


@pytest.fixture
def checkout(tmp_path):
    """A copy of the workflow and the package (Snakefile, rules, the rules' environment, stages, lib, schemas, config,
    profiles)."""
    copy = tmp_path / "posefix"
    copy.mkdir()
    for name in ("Snakefile", "config.yaml"):
        shutil.copy(ROOT / name, copy / name)
    for name in ("rules", "envs", "stages", "lib", "schemas", "profiles", "examples"):
        shutil.copytree(ROOT / name, copy / name, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    return copy


def balls(folder, names):
    V, F = icosphere(2)
    write_mesh(folder / "ball-reference.obj", V, F)
    for name in names:
        write_mesh(folder / f"{name}.obj", V * SHAPES[name], F)
    return folder


def command(checkout, work, *args):
    return [sys.executable, "-m", "snakemake", "-s", str(checkout / "Snakefile"), "--directory", str(work),
            "--cores", "2", *map(str, args)]


def run(checkout, work, *args):
    env = {**os.environ, "PYTHONPATH": str(checkout / "lib")}
    return subprocess.run(command(checkout, work, *args), capture_output=True, text=True, timeout=900, env=env)


def planned(checkout, work, *args):
    """{rule: count} of the jobs a dry run plans."""
    proc = run(checkout, work, "-n", "--quiet", "rules", *args)
    assert proc.returncode == 0, proc.stderr[-3000:]
    jobs = {}
    for line in (proc.stdout + proc.stderr).splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[1].isdigit() and parts[0] not in ("job", "total"):
            jobs[parts[0]] = int(parts[1])
    return jobs


def test_adding_a_pose_plans_only_that_pose_and_a_code_change_only_what_it_changes(checkout, tmp_path):
    library = balls(tmp_path / "lib", ["ball-01", "ball-02"])  # two, then a third, with the contact repair beside
    config = ["--config", f"library={library}", "repairs=[contact]"]
    proc = run(checkout, tmp_path, *config)
    assert proc.returncode == 0, proc.stderr[-3000:]
    V, F = icosphere(2)
    write_mesh(library / "ball-04.obj", V * SHAPES["ball-04"], F)
    jobs = planned(checkout, tmp_path, *config)
    per_pose = {"validate", "keyframes", "classify", "constraints", "fit", "integrate", "verify", "export",
                "downstream", "render", "repair_contact", "export_repair"}
    assert set(jobs) == per_pose | {"summary", "overview", "viewer", "all"}
    assert all(jobs[rule] == 1 for rule in per_pose)
    proc = run(checkout, tmp_path, *config)
    assert proc.returncode == 0, proc.stderr[-3000:]
    # a comment in the library module of the verify stage: verify and what reads its output rerun, and integrate, whose
    # output verify reads and Snakemake removed (an intermediate), nothing else
    module = checkout / "lib" / "posefix" / "verify" / "sequence.py"
    module.write_text(module.read_text() + "\n# a comment\n")
    jobs = planned(checkout, tmp_path, *config)
    assert set(jobs) == {"integrate", "verify", "export", "downstream", "render", "summary", "overview", "viewer", "all"}
    assert jobs["verify"] == 3 and jobs["integrate"] == 3


def digests(folder):
    """sha256 of every file below ``folder`` (logs and Snakemake's benchmark files aside)."""
    import hashlib
    return {p.relative_to(folder): hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.rglob("*"))
            if p.is_file() and not {"logs", "benchmarks"} & set(p.relative_to(folder).parts)}


def test_a_bad_pose_fails_alone_with_one_line_and_earlier_results_stay(checkout, tmp_path):
    library = balls(tmp_path / "lib", ["ball-01"])
    assert run(checkout, tmp_path, "--config", f"library={library}", "repairs=[]").returncode == 0
    results = tmp_path / "results" / "lib"
    before = digests(results)
    V, F = icosphere(2)
    write_mesh(library / "ball-02.ply", np.vstack([V, [[9.0, 9.0, 9.0]]]), F)  # one vertex too many
    write_mesh(library / "ball-03.obj", V * SHAPES["ball-03"], F)
    proc = run(checkout, tmp_path, "--config", f"library={library}", "repairs=[]")
    assert proc.returncode != 0
    errors = [line for line in proc.stderr.splitlines() if line.startswith("posefix validate: error:")]
    assert len(errors) == 1 and "ball-02.ply" in errors[0] and "vertices" in errors[0]
    assert "Traceback" not in proc.stderr
    assert (results / "repaired" / "ball-03.obj").exists() and not list(results.glob("ball-02/*.h5"))
    after = digests(results)
    assert all(after[name] == digest for name, digest in before.items())  # nothing earlier rewritten


def test_a_run_killed_during_the_fit_finishes_with_the_same_command(checkout, tmp_path):
    library = balls(tmp_path / "lib", ["ball-01"])
    config = ["--config", f"library={library}", "repairs=[]"]
    reference = tmp_path / "reference"
    assert run(checkout, reference, *config).returncode == 0
    env = {**os.environ, "PYTHONPATH": str(checkout / "lib")}
    work = tmp_path / "killed"
    started = subprocess.Popen(command(checkout, work, *config), env=env, start_new_session=True,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    fit_log = work / "results" / "lib" / "logs" / "ball-01" / "fit.log"
    deadline = time.time() + 300
    while not (fit_log.exists() and fit_log.stat().st_size > 0) and time.time() < deadline:
        time.sleep(0.05)
    os.killpg(started.pid, signal.SIGKILL)
    started.wait()
    assert any((work / ".snakemake" / "locks").glob("*.lock"))  # what a hard kill leaves
    proc = run(checkout, work, *config)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "removed 2 stale Snakemake lock(s)" in proc.stderr
    name = "results/lib/repaired/ball-01.obj"
    assert (work / name).read_bytes() == (reference / name).read_bytes()


@pytest.mark.parametrize("setting, line", [
    ("keyframes={'count': 1}", "posefix: error: config: keyframes.count: 1 is less than the minimum of 2"),
    ("fitt=3", "posefix: error: config: fitt: unknown key (did you mean 'fit'?)"),
])
def test_a_config_mistake_is_one_line_naming_the_key(checkout, tmp_path, setting, line):
    proc = run(checkout, tmp_path, "-n", "--config", setting)
    assert proc.returncode != 0 and line in proc.stderr.splitlines()
    assert len(proc.stderr.splitlines()) < 10 and not (tmp_path / "results").exists()


def test_a_library_split_along_a_seam_is_repaired_welded_and_split_again(checkout, tmp_path, demo, demo_run):
    from posefix.io.meshes import read_mesh
    V, F, poses = demo
    F2, shared, copies = split_along_a_seam(V, F)
    library = tmp_path / "seams"
    for name, X in (("demo-reference", V), ("demo-01", poses["demo-01"])):
        write_mesh(library / f"{name}.obj", np.vstack([X, X[shared]]), F2)
    proc = run(checkout, tmp_path, "--config", f"library={library}", "repairs=[]")
    assert proc.returncode == 0, proc.stderr[-3000:]
    out, F_out = read_mesh(tmp_path / "results" / "seams" / "repaired" / "demo-01.obj")
    assert np.array_equal(F_out, F2) and len(out) == len(V) + len(shared)
    assert np.array_equal(out[copies], out[shared])  # the seam stays closed, bit for bit
    # welded, the computation is the unsplit demo's: the same repaired pose, the same fit
    welded, _ = read_mesh(demo_run / "results" / "demo" / "repaired" / "demo-01.obj")
    assert np.array_equal(out[: len(V)], welded)
    import h5py
    with h5py.File(tmp_path / "results" / "seams" / "demo-01" / "fit.h5", "r") as a, \
            h5py.File(demo_run / "results" / "demo" / "demo-01" / "fit.h5", "r") as b:
        assert np.array_equal(a["history/condition"][()], b["history/condition"][()])
    opened = np.vstack([poses["demo-02"], poses["demo-02"][shared]])
    opened[copies[5]] += [0.0, 0.0, 0.1]  # the seam opens in this pose
    write_mesh(library / "demo-02.obj", opened, F2)
    proc = run(checkout, tmp_path, "--config", f"library={library}", "repairs=[]", "poses=demo-02")
    errors = [line for line in proc.stderr.splitlines() if line.startswith("posefix validate: error:")]
    assert proc.returncode != 0 and len(errors) == 1
    assert f"demo-02.obj: vertices {shared[5]} and {copies[5]} coincide in the reference (a seam)" in errors[0]
