"""The Blender add-on (issue 49, item 3), headless: bpy 4.5 LTS in an environment of its own (``.venv-blender``, which
``make test`` makes: bpy pins numpy < 2 and Python 3.11), the add-on's zip installed as Blender's preferences install
it, *Repair shape keys* on the demo limb (362 vertices) with its 4 poses as shape keys. The repair runs in this
environment's Python (the add-on's preference), as a background process."""

import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from conftest import ROOT
from posefix import __version__
from posefix.io.meshes import read_mesh, write_mesh
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.workflow.blender_addon import MANIFEST, build_addon
from posefix.workflow.demo import demo_library

BLENDER_PYTHON = Path(os.environ.get("POSEFIX_BLENDER_PYTHON", ROOT / ".venv-blender" / "bin" / "python"))
"""The Python of the bpy environment."""


def _bpy_missing():
    """Why bpy cannot run here (str), or None."""
    if not BLENDER_PYTHON.is_file():
        return f"no bpy environment at {BLENDER_PYTHON} (make test makes it where Python 3.11 is available)"
    proc = subprocess.run([BLENDER_PYTHON, "-c", "import bpy"], capture_output=True, text=True)
    return None if proc.returncode == 0 else f"{BLENDER_PYTHON} cannot import bpy: {proc.stderr.strip()[-200:]}"


needs_bpy = pytest.mark.skipif(_bpy_missing() is not None, reason=str(_bpy_missing()))


@pytest.fixture(scope="module")
def limb(tmp_path_factory):
    """The demo limb at float32 (as Blender stores it): ``(npz path, arrays, library folder)``; the folder holds the
    same reference and poses as OBJ files."""
    folder = tmp_path_factory.mktemp("limb")
    V, F, poses = demo_library(around=12)
    f32 = lambda a: a.astype(np.float32).astype(np.float64)  # noqa: E731
    arrays = {"reference": f32(V), "faces": F, "poses": np.stack([f32(p) for p in poses.values()]),
              "names": np.array(list(poses))}
    np.savez(folder / "limb.npz", **arrays)
    library = folder / "limb"
    library.mkdir()
    write_mesh(library / "limb-reference.obj", arrays["reference"], F)
    for name, pose in zip(arrays["names"], arrays["poses"]):
        write_mesh(library / f"{name}.obj", pose, F)
    return folder / "limb.npz", arrays, library


@pytest.fixture(scope="module")
def folder_run(limb, tmp_path_factory):
    """The folder's repaired meshes (posefix.repair_library, space-time, one downstream step): {pose: (n, 3)}."""
    out = tmp_path_factory.mktemp("folder-run")
    code = (f"import posefix; posefix.repair_library({str(limb[2])!r}, out={str(out)!r}, "
            "config={'downstream.max_iters': 1})")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return {str(name): read_mesh(out / "results" / "limb" / "repaired" / f"{name}.obj")[0] for name in limb[1]["names"]}


@pytest.fixture(scope="module")
def addon(tmp_path_factory):
    return build_addon(tmp_path_factory.mktemp("addon"))


def _scene(action, limb, addon, tmp_path):
    """scene.py's ``action`` in the bpy environment (a Blender home of its own): (OUT.json, OUT.npz arrays)."""
    env = dict(os.environ, HOME=str(tmp_path / "home"))
    proc = subprocess.run([BLENDER_PYTHON, ROOT / "tests" / "blender" / "scene.py", action, limb[0], tmp_path / action,
                           addon, sys.executable], capture_output=True, text=True, env=env, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    info = json.loads((tmp_path / f"{action}.json").read_text())
    npz = tmp_path / f"{action}.npz"
    return info, (dict(np.load(npz)) if npz.is_file() else None)


def _new_faces(X, arrays):
    F = arrays["faces"]
    reference = intersecting_faces(self_intersecting_pairs(arrays["reference"], F), len(F))
    return int((intersecting_faces(self_intersecting_pairs(X.astype(np.float64), F), len(F)) & ~reference).sum())


@pytest.mark.pipeline
@needs_bpy
def test_repair_as_new_keys_writes_the_folder_runs_meshes_and_keeps_each_keys_settings(limb, folder_run, addon,
                                                                                       tmp_path):
    info, keys = _scene("new", limb, addon, tmp_path)
    arrays = limb[1]
    assert info["result"] == ["FINISHED"]
    for k, name in enumerate(arrays["names"]):
        repaired = keys[f"{name}.repaired"]
        assert np.array_equal(repaired, folder_run[name].astype(np.float32)), name
        assert _new_faces(repaired, arrays) == 0 and _new_faces(arrays["poses"][k], arrays) > 0
        assert np.array_equal(keys[name], arrays["poses"][k].astype(np.float32))  # the key itself unchanged
        assert info["keys"][f"{name}.repaired"] == info["keys"][name]  # relative key, value, mute
    assert info["keys"]["demo-02.repaired"]["mute"] and info["keys"]["demo-03.repaired"]["relative_key"] == "demo-01"
    assert [r["status"] for r in info["results"]] == ["ok"] * 4


@pytest.mark.pipeline
@needs_bpy
def test_repair_in_place_replaces_the_named_keys_alone(limb, folder_run, addon, tmp_path):
    info, keys = _scene("in_place", limb, addon, tmp_path)
    arrays = limb[1]
    assert info["result"] == ["FINISHED"] and not any(name.endswith(".repaired") for name in keys)
    for k, name in enumerate(arrays["names"]):
        expected = folder_run[name] if name in ("demo-02", "demo-04") else arrays["poses"][k]
        assert np.array_equal(keys[name], expected.astype(np.float32)), name
    assert [r["name"] for r in info["results"]] == ["demo-02", "demo-04"]


@needs_bpy
def test_bad_input_is_one_line_in_blenders_report_and_changes_nothing(limb, addon, tmp_path):
    info, _ = _scene("bad", limb, addon, tmp_path)
    assert info == {
        "no shape keys": {"line": "Error: bare: no shape keys to repair (the basis is the reference, every other key "
                                  "a pose)", "changed": False},
        "a non-mesh object": {"line": "Error: camera is a camera, not a mesh", "changed": False},
        "a key with another vertex count": {"line": "Error: grown: shape key 'Basis' has 362 vertices, the mesh 363",
                                            "changed": False},
        "modifiers that change the topology": {
            "line": "Error: subdivided: modifiers change the mesh's vertices or faces ('Subdivision' (subsurf)): apply "
                    "or disable them first (the shape keys are the mesh's own vertices)", "changed": False},
        "no posefix environment": {"line": "Error: posefix Python /nonexistent/python: no such file (set the posefix "
                                           "Python in the add-on's preferences)", "changed": False}}


def test_the_addons_zip_has_its_manifest_at_the_root_with_posefixs_version(addon):
    with zipfile.ZipFile(addon) as archive:
        names = set(archive.namelist())
        manifest = archive.read(MANIFEST).decode()
    assert {MANIFEST, "__init__.py", "shape_keys.py", "job.py"} <= names
    assert f'version = "{__version__}"' in manifest.splitlines()
    assert not any("__pycache__" in name for name in names)
