"""Alembic caches (issue 49, item 4), read and written by Blender in the bpy environment (``.venv-blender``, made by
make test): frames read exactly as Blender's exporter wrote them and written back with only the repaired frames
changed (float32); every cache that is no pose library, and no Blender at all, one line each."""

import subprocess

import numpy as np
import pytest

from conftest import ROOT, icosphere
from containers import write_alembic_frames
from posefix.io.containers import open_container
from posefix.io.errors import InputError
from posefix.io.formats.alembic import BLENDER_VARIABLE

BLENDER_PYTHON = ROOT / ".venv-blender" / "bin" / "python"
needs_bpy = pytest.mark.skipif(not BLENDER_PYTHON.is_file(), reason=f"no bpy environment at {BLENDER_PYTHON} (make "
                               "test makes it where Python 3.11 is available)")


@pytest.fixture(autouse=True)
def blender(monkeypatch):
    monkeypatch.setenv(BLENDER_VARIABLE, str(BLENDER_PYTHON))


def f32(X):
    return np.asarray(X, dtype=np.float32).astype(np.float64)


@needs_bpy
def test_frames_read_exactly_and_write_back_only_the_repaired_ones(tmp_path):
    V, F = icosphere(1)
    poses = [V * 1.1, V + 0.1]
    box = open_container(write_alembic_frames(tmp_path / "walk.abc", V, poses, F))
    assert list(box.members.items()) == [("walk-1", 1.0), ("walk-2", 2.0), ("walk-3", 3.0)] and box.rest is None
    assert box.mesh == "Body" and box.n == len(V) and np.array_equal(box.faces, F)
    for name, P in zip(box.members, [V, *poses]):
        assert np.array_equal(box.points(name), f32(P)) and box.where(name) == f"mesh Body, frame {name[-1]}"
    repaired = poses[1] + 0.01 * np.sin(np.arange(len(V)))[:, None]
    (tmp_path / "out").mkdir()
    box.write(tmp_path / "out" / "walk.abc", {"walk-3": repaired})
    back = open_container(tmp_path / "out" / "walk.abc")
    assert list(back.members.items()) == list(box.members.items()) and back.mesh == box.mesh
    assert np.array_equal(back.faces, F) and np.array_equal(back.points("walk-3"), f32(repaired))
    assert all(np.array_equal(back.points(m), box.points(m)) for m in ("walk-1", "walk-2"))


def _case(tmp_path, case):
    out = tmp_path / f"{case}.abc"
    subprocess.run([BLENDER_PYTHON, ROOT / "tests" / "blender" / "alembic_cases.py", case, out], check=True,
                   capture_output=True)
    return out


@needs_bpy
@pytest.mark.parametrize("case, mesh, line", [
    ("empty", None, "{path}: no mesh in the cache"),
    ("changing", None, "{path}: mesh Sphere: frame 2 has 74 vertices and 100 faces, frame 1 114 and 128: its topology "
                       "changes between frames"),
    ("two", None, "{path}: 2 meshes (Cube, Sphere): choose one with the config's mesh: <name>"),
    ("two", "Body", "{path}: no mesh Body (meshes: Cube, Sphere)"),
])
def test_a_cache_that_is_no_pose_library_is_one_line(tmp_path, case, mesh, line):
    path = _case(tmp_path, case)
    with pytest.raises(InputError) as caught:
        open_container(path, mesh)
    assert str(caught.value) == line.format(path=path)


@needs_bpy
def test_a_truncated_or_foreign_file_is_one_line(tmp_path):
    V, F = icosphere(1)
    whole = write_alembic_frames(tmp_path / "whole.abc", V, [V * 1.1], F).read_bytes()
    (tmp_path / "cut.abc").write_bytes(whole[:len(whole) // 2])
    (tmp_path / "notes.abc").write_text("not alembic")
    with pytest.raises(InputError) as caught:
        open_container(tmp_path / "cut.abc")
    assert str(caught.value) == (f"{tmp_path / 'cut.abc'}: cannot be read as Alembic: Blender stopped on it (Ogawa "
                                 "IStreams::read failed.); a damaged or truncated file?")
    with pytest.raises(InputError) as caught:
        open_container(tmp_path / "notes.abc")
    assert str(caught.value) == (f"{tmp_path / 'notes.abc'}: cannot be read as Alembic (Blender's importer found no "
                                 "archive or nothing in it)")


def test_without_blender_the_line_says_what_to_install(tmp_path, monkeypatch):
    monkeypatch.delenv(BLENDER_VARIABLE)
    monkeypatch.setenv("PATH", str(tmp_path))
    (tmp_path / "walk.abc").write_bytes(b"")
    with pytest.raises(InputError) as caught:
        open_container(tmp_path / "walk.abc")
    assert str(caught.value) == (
        f"{tmp_path / 'walk.abc'}: Alembic caches are read and written by Blender: install Blender 4.2 or later (the "
        "blender command), or bpy 4.5 in a Python 3.11 environment of its own (make .venv-blender), and name it in "
        "$POSEFIX_BLENDER")
