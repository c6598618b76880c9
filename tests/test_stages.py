"""Stage command lines and artifacts: --help, provenance attributes, documented datasets, determinism."""

import json
import re
from pathlib import Path

import h5py
import numpy as np
import pytest

from conftest import ROOT, run_stage
from posefix import __version__
from posefix.io.artifacts import config_hash, inputs_hash
from posefix.io.keyframes import read_keyframes

STAGES = ["demo", "validate", "keyframes", "classify", "constraints", "fit", "integrate", "verify", "export",
          "downstream", "summary", "render", "overview", "skeletal_pose", "skeleton", "repair_medial",
          "volumetric_pose", "tet_mesh", "repair_volumetric", "volumetric_animate", "viewer", "unpack", "pack"]


def test_the_dataset_tables_of_the_artifacts_page_are_the_artifact_schema():
    """Each dataset is described once, in schemas/artifacts.yaml (also stored as the dataset's attributes)."""
    from artifact_docs import stage_docs, with_tables
    page = (ROOT / "docs" / "artifacts.md").read_text()
    assert with_tables(page, stage_docs()) == page, "docs/artifacts.md is stale: python tests/artifact_docs.py"


def documented_datasets():
    """Dataset name patterns per stage from the tables of docs/artifacts.md (``<k>``: any suffix)."""
    text = (ROOT / "docs" / "artifacts.md").read_text()
    out = {}
    for section in re.split(r"\n## ", text)[1:]:
        stage = section.split()[0]
        out[stage] = set(re.findall(r"^\| `([^`]+)` \|", section, flags=re.M))
    return out


def _pattern(doc):
    return re.compile(re.escape(doc).replace(re.escape("<k>"), r"\d+") + "$")


def undocumented(names, patterns):
    """Dataset names that match no documented pattern."""
    return {n for n in names if not any(_pattern(p).match(n) for p in patterns)}


def unwritten(names, patterns):
    """Documented patterns that match no dataset."""
    return {p for p in patterns if not any(_pattern(p).match(n) for n in names)}


@pytest.mark.parametrize("stage", STAGES)
def test_help(stage):
    proc = run_stage(stage, "--help")
    assert f"usage: {stage}.py" in proc.stdout and "--threads" in proc.stdout
    text = " ".join(proc.stdout.split())  # argparse wraps the help
    for wrong in ("(default: None)", "(default: True)", "(default: False)", "(default: [])"):
        assert wrong not in text, f"{stage}.py --help: {wrong}"
    assert not re.search(r"\(default: [^)]*\) \(default:", text), f"{stage}.py --help: a default said twice"


@pytest.fixture(scope="module")
def demo_artifacts(tmp_path_factory):
    """Every per-pose stage run by hand on demo-01 (K = 5, a small fit)."""
    tmp = tmp_path_factory.mktemp("stages")
    run_stage("demo", "--out", tmp / "lib")
    ref, tgt = tmp / "lib" / "demo-reference.obj", tmp / "lib" / "demo-01.obj"
    run_stage("validate", "--library", tmp / "lib", "--out", tmp / "library.h5")
    run_stage("keyframes", "--reference", ref, "--target", tgt, "--count", 5, "--out", tmp / "keyframes.h5")
    run_stage("classify", "--keyframes", tmp / "keyframes.h5", "--ring", 1, "--contact", 0.01,
              "--out", tmp / "classify.h5")
    run_stage("constraints", "--keyframes", tmp / "keyframes.h5", "--classify", tmp / "classify.h5",
              "--samples", 4, "--out", tmp / "constraints.h5")
    run_stage("fit", "--constraints", tmp / "constraints.h5", "--max-centers", 400, "--batch", 64,
              "--out", tmp / "fit.h5")
    run_stage("integrate", "--fit", tmp / "fit.h5", "--keyframes", tmp / "keyframes.h5", "--out", tmp / "integrate.h5")
    run_stage("verify", "--keyframes", tmp / "keyframes.h5", "--classify", tmp / "classify.h5",
              "--integrate", tmp / "integrate.h5", "--fit", tmp / "fit.h5", "--out", tmp / "verify.h5")
    run_stage("downstream", "--keyframes", tmp / "keyframes.h5", "--verify", tmp / "verify.h5", "--alphas", 1.0,
              "--k-bend", "0.01,0.1", "--max-iters", 4, "--out", tmp / "downstream.h5", "--png", tmp / "downstream.png")
    run_stage("skeleton", "--reference", ref, "--out", tmp / "skeleton.h5")
    run_stage("repair_medial", "--reference", ref, "--target", tgt, "--skeleton", tmp / "skeleton.h5",
              "--out", tmp / "repair_medial.h5")
    run_stage("volumetric_pose", "--mesh", ref, "--script", ROOT / "examples" / "demo-limb-volumetric.yaml",
              "--out", tmp / "authored", "--artifact", tmp / "volumetric_pose.h5", "--tet-vertices", 300)
    run_stage("volumetric_animate", "--mesh", ref, "--tracks", ROOT / "examples" / "demo-limb-markers.csv",
              "--out", tmp / "animated", "--artifact", tmp / "volumetric_animate.h5", "--tet-vertices", 300)
    run_stage("tet_mesh", "--reference", ref, "--out", tmp / "tet_mesh.h5", "--tet-vertices", 300)
    run_stage("repair_volumetric", "--reference", ref, "--target", tgt, "--classify", tmp / "classify.h5",
              "--tets", tmp / "tet_mesh.h5", "--out", tmp / "repair_volumetric.h5", "--max-rings", 2)
    return tmp


@pytest.mark.parametrize("stage", ["validate", "keyframes", "classify", "constraints", "fit", "integrate", "verify",
                                   "downstream", "skeleton", "repair_medial", "volumetric_pose",
                                   "tet_mesh", "repair_volumetric", "volumetric_animate"])
def test_artifact_attributes_and_documentation(demo_artifacts, stage):
    path = demo_artifacts / ("library.h5" if stage == "validate" else f"{stage}.h5")
    docs = documented_datasets()[stage]
    with h5py.File(path, "r") as fh:
        assert fh.attrs["stage"] == stage and fh.attrs["posefix_version"] == __version__
        assert fh.attrs["config_sha256"] == config_hash(json.loads(fh.attrs["config"]))
        assert fh.attrs["inputs_sha256"] == inputs_hash(json.loads(fh.attrs["inputs"]))
        assert len(fh["timings"].attrs) >= 2 and all(v >= 0 for v in fh["timings"].attrs.values())
        names = []
        fh.visititems(lambda name, obj: names.append(name) if isinstance(obj, h5py.Dataset) else None)
        assert not undocumented(names, docs) and not unwritten(names, docs)
        for name in names:
            assert fh[name].attrs["description"] and "units" in fh[name].attrs


def test_downstream_runs_every_setting_towards_both_examples(demo_artifacts):
    from posefix.downstream.gauss_newton import STOP_REASONS
    with h5py.File(demo_artifacts / "downstream.h5", "r") as fh:
        assert fh["alpha"][()].tolist() == [1.0] * 4 and fh["k_bend"][()].tolist() == [0.01, 0.01, 0.1, 0.1]
        assert fh["example"][()].tolist() == [0, 1, 0, 1]
        iterations, offsets = fh["iterations"][()], fh["error_offsets"][()]
        assert np.all((iterations >= 1) & (iterations <= 4)) and np.array_equal(np.diff(offsets), iterations + 1)
        errors = fh["errors"][()]
        for i in range(4):  # every accepted step lowers the energy
            assert np.all(np.diff(errors[offsets[i]:offsets[i + 1]]) < 0)
        reasons = [STOP_REASONS[r] for r in fh["reason"][()]]
        assert fh["converged"][()].tolist() == [r == "converged" for r in reasons]
        metrics = fh["metrics"].attrs
        assert metrics["runs"] == 4 and metrics["original_iterations"] == iterations[[0, 2]].sum()
    assert (demo_artifacts / "downstream.png").stat().st_size > 10_000


def test_downstream_with_threads_runs_the_grid_in_parallel_to_the_same_results(demo_artifacts, tmp_path):
    run_stage("downstream", "--keyframes", demo_artifacts / "keyframes.h5", "--verify", demo_artifacts / "verify.h5",
              "--alphas", 1.0, "--k-bend", "0.01,0.1", "--max-iters", 4, "--threads", 2, "--out", tmp_path / "d.h5")
    with h5py.File(demo_artifacts / "downstream.h5", "r") as serial, h5py.File(tmp_path / "d.h5", "r") as parallel:
        assert set(serial) == set(parallel)
        for name in set(serial) - {"seconds", "metrics", "timings"}:
            a, b = serial[name][()], parallel[name][()]
            assert (a.tolist() == b.tolist()) if a.dtype == object else (a.tobytes() == b.tobytes()), name


@pytest.fixture(scope="module")
def medial(demo_artifacts):
    """Another repair's artifact as stage repair_medial writes it (the datasets the report reads), whose
    repaired pose is S0's (verify.h5's)."""
    from posefix.io.artifacts import write_artifact
    with h5py.File(demo_artifacts / "keyframes.h5", "r") as fh:
        target = fh["target"][()]
    with h5py.File(demo_artifacts / "verify.h5", "r") as fh:
        X = fh["repaired"][()]
    path = demo_artifacts / "medial.h5"
    write_artifact(path, "repair_medial", {"start": target, "repaired": X}, params={}, inputs=[], timings={},
                   metrics={"iterations": 3, "best": 3, "seconds": 1.0, "intersecting_faces_target": 0,
                            "intersecting_faces_repaired": 0, "intersecting_faces_repaired_new": 0})
    return path


def test_downstream_checks_another_repair_as_a_third_example(demo_artifacts, medial, tmp_path):
    run_stage("downstream", "--keyframes", demo_artifacts / "keyframes.h5", "--verify", demo_artifacts / "verify.h5",
              "--alphas", 1.0, "--k-bend", 0.01, "--max-iters", 4, "--repair", f"medial={medial}",
              "--out", tmp_path / "d.h5", "--png", tmp_path / "d.png")
    with h5py.File(tmp_path / "d.h5", "r") as fh:
        assert fh["example"][()].tolist() == [0, 1, 2]
        assert [n.decode() for n in fh["examples"][()]] == ["original", "repaired", "medial"]
        iterations, offsets, errors = fh["iterations"][()], fh["error_offsets"][()], fh["errors"][()]
        # the same grid towards the same pose: the other repair's run is the repaired one, step for step
        assert iterations[2] == iterations[1] >= 1
        assert np.array_equal(errors[offsets[2]:offsets[3]], errors[offsets[1]:offsets[2]])
        assert fh["metrics"].attrs["medial_iterations"] == iterations[2] and fh["metrics"].attrs["runs"] == 3
        assert str(medial) in json.loads(fh.attrs["inputs"])
    proc = run_stage("downstream", "--keyframes", demo_artifacts / "keyframes.h5", "--verify",
                     demo_artifacts / "verify.h5", "--repair", f"medial={demo_artifacts / 'verify.h5'}",
                     "--out", tmp_path / "e.h5", check=False)
    assert proc.returncode == 2 and "not a 'repair_medial' artifact" in proc.stderr and not (tmp_path / "e.h5").exists()


def test_render_draws_the_other_repair_beside_s0(demo_artifacts, medial, tmp_path):
    from matplotlib.image import imread
    common = ["--keyframes", demo_artifacts / "keyframes.h5", "--classify", demo_artifacts / "classify.h5",
              "--fit", demo_artifacts / "fit.h5", "--verify", demo_artifacts / "verify.h5",
              "--benchmarks", tmp_path, "--pose", "demo-01"]
    run_stage("render", *common, "--out", tmp_path / "two")
    run_stage("render", *common, "--repair", f"medial={medial}", "--out", tmp_path / "three")
    two, three = imread(tmp_path / "two" / "renders.png"), imread(tmp_path / "three" / "renders.png")
    assert three.shape[0] == two.shape[0] and abs(three.shape[1] - 1.5 * two.shape[1]) <= 2  # a third panel
    for name in ("deviation", "classification", "fit"):  # the other figures do not change
        assert np.array_equal(imread(tmp_path / "two" / f"{name}.png"), imread(tmp_path / "three" / f"{name}.png"))


def test_keyframes_and_classify_contents(demo_artifacts):
    with h5py.File(demo_artifacts / "keyframes.h5", "r") as fh:
        t, offsets, metrics = fh["t"][()], fh["frame_offsets"], fh["metrics"].attrs
        assert np.array_equal(t, [0, 0.25, 0.5, 0.75, 1]) and offsets.shape[0] == 3 and offsets.dtype == np.float32
        assert max(metrics["endpoint_error_reference"], metrics["endpoint_error_target"]) < 1e-9
    frames = read_keyframes(demo_artifacts / "keyframes.h5", ["frames"])[0]["frames"]
    assert frames.shape[0] == 5 and np.abs(frames[2] - frames[0]).max() > 0.01  # the inner frames move
    with h5py.File(demo_artifacts / "classify.h5", "r") as fh:
        offsets, counts = fh["pair_offsets"][()], fh["intersecting_faces"][()]
        assert len(offsets) == 6 and offsets[-1] == len(fh["pairs"])
        assert counts[0] == 0 and counts[-1] > 0
        mask, reasons = fh["mask"][()], fh["reasons"][()]
        readded = (reasons & 16 > 0) & (reasons & 8 == 0)
        assert np.array_equal(mask, ((reasons & 15) == 0) | readded)
        assert fh["metrics"].attrs["constraint_vertices"] == mask.sum()
        assert fh["contact_vertices"][()].max() > 0


def test_stages_are_deterministic(demo_artifacts, tmp_path):
    ref = demo_artifacts / "lib" / "demo-reference.obj"
    tgt = demo_artifacts / "lib" / "demo-01.obj"
    run_stage("keyframes", "--reference", ref, "--target", tgt, "--count", 5, "--out", tmp_path / "k.h5")
    run_stage("classify", "--keyframes", tmp_path / "k.h5", "--contact", 0.01, "--out", tmp_path / "c.h5")
    for a, b in (("keyframes.h5", "k.h5"), ("classify.h5", "c.h5")):
        with h5py.File(demo_artifacts / a, "r") as fa, h5py.File(tmp_path / b, "r") as fb:
            for name in fa:
                if isinstance(fa[name], h5py.Dataset):
                    assert np.array_equal(fa[name][()], fb[name][()]), name


def test_verify_names_the_pose_whose_repair_left_something_and_what(demo_artifacts, tmp_path):
    """The snap finish of this small fit takes the target back where key frames pass through each other, its
    intersections with it: one warning naming the pose file and both; the contact finish leaves nothing to say."""
    inputs = [f"--{k}={demo_artifacts / f'{k}.h5'}" for k in ("keyframes", "classify", "integrate", "fit")]
    proc = run_stage("verify", *inputs, "--finish", "snap", "--out", tmp_path / "snap.h5")
    with h5py.File(tmp_path / "snap.h5", "r") as fh:
        new, taken = int(fh["metrics"].attrs["repaired_new"]), int(fh["metrics"].attrs["fallback_pass_through"])
    assert new > 0 and taken > 0
    warnings = [line for line in proc.stderr.splitlines() if "warning" in line]
    assert len(warnings) == 1 and warnings[0].endswith(
        f"posefix verify: warning: {demo_artifacts / 'lib' / 'demo-01.obj'}: {new} new intersecting faces remain; "
        f"{taken} vertices are the target's (pass-through: key frames pass through each other there); see the "
        "report's pose page"), warnings
    proc = run_stage("verify", *inputs, "--out", tmp_path / "contact.h5")
    assert "warning" not in proc.stderr


def test_manual_exclusion_from_a_file(demo_artifacts, tmp_path):
    ids = tmp_path / "ids.txt"
    ids.write_text("0 1 2\n")
    run_stage("classify", "--keyframes", demo_artifacts / "keyframes.h5", "--exclude-file", ids,
              "--exclude", "5", "--out", tmp_path / "c.h5")
    with h5py.File(tmp_path / "c.h5", "r") as fh:
        assert not fh["mask"][()][[0, 1, 2, 5]].any()
    ids.write_text("0 99999\n")
    proc = run_stage("classify", "--keyframes", demo_artifacts / "keyframes.h5", "--exclude-file", ids,
                     "--out", tmp_path / "d.h5", check=False)
    assert proc.returncode == 2 and "ids.txt: vertex id 99999 out of range" in proc.stderr
    assert not (tmp_path / "d.h5").exists()


def test_classify_rejects_a_wrong_artifact(demo_artifacts, tmp_path):
    proc = run_stage("classify", "--keyframes", demo_artifacts / "library.h5", "--out", tmp_path / "c.h5",
                     check=False)
    assert proc.returncode == 2 and "not a 'keyframes' artifact" in proc.stderr
    Path(tmp_path / "junk.h5").write_text("not hdf5")
    proc = run_stage("classify", "--keyframes", tmp_path / "junk.h5", "--out", tmp_path / "c.h5", check=False)
    assert proc.returncode == 2 and "cannot be read as HDF5" in proc.stderr


def test_export_reproduces_the_target_file_but_the_vertex_lines(demo_artifacts, tmp_path):
    target = demo_artifacts / "lib" / "demo-01.obj"
    run_stage("export", "--artifact", demo_artifacts / "verify.h5", "--reference", demo_artifacts / "lib" /
              "demo-reference.obj", "--target", target, "--out", tmp_path / "r.obj")
    with h5py.File(demo_artifacts / "verify.h5", "r") as fh:
        X = fh["repaired"][()]
    ours, theirs = (tmp_path / "r.obj").read_text().splitlines(), target.read_text().splitlines()
    assert len(ours) == len(theirs)
    assert [a for a in ours if not a.startswith("v ")] == [b for b in theirs if not b.startswith("v ")]
    V = np.array([[float(x) for x in a.split()[1:4]] for a in ours if a.startswith("v ")])
    assert np.array_equal(V, X)  # round trip without loss


def test_export_refuses_a_target_of_another_size(demo_artifacts, tmp_path):
    from conftest import icosphere
    from posefix.io.meshes import write_mesh
    V, F = icosphere(1)
    write_mesh(tmp_path / "ball.obj", V, F)
    proc = run_stage("export", "--artifact", demo_artifacts / "verify.h5", "--reference",
                     demo_artifacts / "lib" / "demo-reference.obj", "--target", tmp_path / "ball.obj",
                     "--out", tmp_path / "r.obj", check=False)
    assert proc.returncode == 2 and "ball.obj" in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "r.obj").exists()


@pytest.fixture(scope="module")
def authored(tmp_path_factory):
    """skeletal_pose on a small demo limb (12 vertices per ring) with the shipped demo rig."""
    from posefix.workflow import demo
    from posefix.io.meshes import write_mesh
    folder = tmp_path_factory.mktemp("authored")
    V, F, _ = demo.demo_library(around=12)
    write_mesh(folder / "limb.obj", V, F)
    args = ["--mesh", folder / "limb.obj", "--rig", ROOT / "examples" / "demo-limb.yaml", "--max-iters", 5]
    run_stage("skeletal_pose", *args, "--out", folder / "lib", "--artifact", folder / "a.h5")
    run_stage("skeletal_pose", *args, "--out", folder / "again", "--artifact", folder / "b.h5")
    return folder, V, F


def test_skeletal_pose_writes_a_library_of_every_pose_and_variant(authored):
    from posefix.io.library import discover_library, read_pose
    folder, V, F = authored
    library = discover_library(folder / "lib")
    assert library.reference.name == "demo-limb-reference"
    assert sorted(p.name for p in library.poses) == sorted(f"demo-0{i}-{v}" for i in range(1, 5)
                                                          for v in ("ssd", "variational", "flow"))
    for pose in library.poses:
        assert read_pose(pose.path, V, F).shape == V.shape
        assert (folder / "again" / Path(pose.path).name).read_bytes() == Path(pose.path).read_bytes()
    with h5py.File(folder / "a.h5") as fh:
        assert fh["intersecting"].shape == (4, 3) and fh["skeleton/S"].shape == V.shape
        assert len(fh["flow/demo-01/intersecting"]) == len(fh["flow/demo-01/step_seconds"]) + 1
        documented = documented_datasets()["skeletal_pose"]
        names = []
        fh.visititems(lambda name, obj: names.append(name) if isinstance(obj, h5py.Dataset) else None)
        flat = {re.sub(r"^flow/[^/]+/", "flow/<pose>/", n) for n in names}
        assert flat == documented


def test_skeletal_pose_rejects_a_bad_rig_in_one_line(authored, tmp_path):
    folder, _, _ = authored
    rig = tmp_path / "bad.yaml"
    rig.write_text("joints: {a: {position: [0, 0, 0]}}\nposes: {p: {rotations: {b: [0, 0, 90]}}}\n")
    proc = run_stage("skeletal_pose", "--mesh", folder / "limb.obj", "--rig", rig, "--out", tmp_path / "out",
                     "--artifact", tmp_path / "a.h5", check=False)
    assert proc.returncode == 2 and proc.stderr.strip().splitlines() == [
        f"posefix skeletal_pose: error: {rig}: pose 'p': unknown joint(s) b"]
    assert not (tmp_path / "out").exists() and not (tmp_path / "a.h5").exists()


def test_an_explicit_device_request_is_honoured_or_fails(demo_artifacts, tmp_path):
    from posefix.spacetime.integration_opencl import select_device
    args = ["--fit", demo_artifacts / "fit.h5", "--keyframes", demo_artifacts / "keyframes.h5", "--out",
            tmp_path / "i.h5", "--device", "gpu"]
    if select_device("gpu")[0] is not None:  # a GPU here: the request is honoured
        run_stage("integrate", *args)
        with h5py.File(tmp_path / "i.h5", "r") as fh:
            assert fh["metrics"].attrs["backend"] == "opencl"
        return
    proc = run_stage("integrate", *args, check=False)
    errors = [line for line in proc.stderr.splitlines() if "error:" in line]
    assert proc.returncode == 2 and len(errors) == 1 and "--device: gpu requested but no gpu" in errors[0]
    assert not (tmp_path / "i.h5").exists()


def test_ctrl_c_during_a_stage_s_imports_exits_quietly_with_130():
    import ast
    import sys
    for stage in STAGES:  # every stage imports the handler before anything but the standard library
        tree = ast.parse((ROOT / "stages" / f"{stage}.py").read_text())
        modules = [node.names[0].name if isinstance(node, ast.Import) else node.module for node in tree.body
                   if isinstance(node, (ast.Import, ast.ImportFrom))]
        first = next(m for m in modules if m.split(".")[0] not in sys.stdlib_module_names)
        assert first == "posefix.workflow.interrupt", stage
    code = ("import os, runpy, signal, sys; import posefix.workflow.interrupt; sys.argv = ['render.py', '--help']; "
            "os.kill(os.getpid(), signal.SIGINT); runpy.run_path(sys.argv[0])")
    import subprocess
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT / "stages")
    assert proc.returncode == 130 and proc.stderr == "posefix render: interrupted; no output written\n"


def test_integrate_refuses_path_lines_that_are_not_finite_in_one_line(demo_artifacts, tmp_path):
    """A field that gives NaN (before: a float32 sphere scaled by 1.1 made one; verify then ended in "cannot convert
    float NaN to integer"): integrate stops with one line naming the fit, and writes nothing."""
    import shutil
    fit = tmp_path / "fit.h5"
    shutil.copy(demo_artifacts / "fit.h5", fit)
    with h5py.File(fit, "r+") as fh:
        fh["weights"][0, 0] = np.nan
    proc = run_stage("integrate", "--fit", fit, "--keyframes", demo_artifacts / "keyframes.h5",
                     "--out", tmp_path / "integrate.h5", check=False)
    lines = [line for line in proc.stderr.splitlines() if "error:" in line]
    assert proc.returncode == 2 and not (tmp_path / "integrate.h5").exists(), proc.stderr
    assert len(lines) == 1 and re.fullmatch(
        rf"posefix integrate: error: {re.escape(str(fit))}: the path lines of \d+ vertices are not finite \(first: "
        r"vertex 0\): the fitted field is degenerate", lines[0]), lines


def test_a_fit_refused_as_nearly_singular_names_the_pose_file_its_constraints_came_from(tmp_path):
    """Constraints near one quadric of space-time (a sphere scaled uniformly, spacetime/test_fit.py): the fit stops
    in one line naming the target pose's mesh file, found back through the artifacts' inputs (constraints.h5 ->
    keyframes.h5 -> the pose), not the temporary constraints.h5."""
    from posefix.io.artifacts import write_artifact
    rng = np.random.default_rng(1)
    x, t = rng.normal(size=(1500, 3)), rng.uniform(0, 1, size=(1500, 1))
    Y = np.hstack([(x / np.linalg.norm(x, axis=1, keepdims=True)) * (1 + 0.1 * t), t]).astype(np.float32)
    pose, keyframes, constraints = tmp_path / "ball-02.obj", tmp_path / "keyframes.h5", tmp_path / "constraints.h5"
    for made in (tmp_path / "ball-reference.obj", pose, tmp_path / "classify.h5"):
        made.write_text("")  # hashed into the artifacts' inputs; not read
    write_artifact(keyframes, "keyframes", {}, params={}, inputs=[tmp_path / "ball-reference.obj", pose], timings={})
    write_artifact(constraints, "constraints", {"points": Y.astype(np.float64), "values": 0.1 * Y[:, :3]},
                   params={}, inputs=[keyframes, tmp_path / "classify.h5"], timings={},
                   metrics={"bbox_diagonal": 2.0})
    proc = run_stage("fit", "--constraints", constraints, "--eps-rel", 1e-10, "--batch", 64,
                     "--checkpoint", tmp_path / "fit.checkpoint", "--out", tmp_path / "fit.h5", check=False)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode != 0 and not (tmp_path / "fit.h5").exists(), proc.stderr
    assert lines[-1].startswith(f"posefix fit: error: {pose}: the fit's system is nearly singular at 64 centres "
                                "(condition number "), lines
