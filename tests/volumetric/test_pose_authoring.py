"""Authoring with S4: pose scripts, region handles, the stage end to end on the demo limb."""

import h5py
import numpy as np
import pytest

from conftest import run_stage
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.workflow import demo
from posefix.io.errors import InputError
from posefix.io.meshes import read_mesh, write_mesh
from posefix.io.pose_scripts import read_pose_script
from posefix.volumetric.authoring import VolumetricPoser, region_tets
from posefix.volumetric.shapes import tet_grid

SCRIPT = """
handles:
  base: {box: [[-0.01, -1, -1], [0.51, 2, 2]]}
  tip: {box: [[9.49, -1, -1], [10.01, 2, 2]]}
rigid:
  middle: {box: [[4.49, -1, -1], [5.51, 2, 2]]}
poses:
  lift: {tip: {translate: [0, 0, 2]}}
  turn: {tip: {rotate: [0, 0, 90], translate: [-3, 3, 0]}, base: {}}
"""


def test_a_pose_script_reads_boxes_and_moves_in_radians(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text(SCRIPT)
    script = read_pose_script(path)
    assert list(script.handles) == ["base", "tip"] and list(script.rigid) == ["middle"]
    assert script.handles["tip"][0] == "box" and np.allclose(script.handles["tip"][1], [[9.49, -1, -1], [10.01, 2, 2]])
    rotate, translate = script.poses["turn"]["tip"]
    assert np.allclose(rotate, [0, 0, np.pi / 2]) and np.allclose(translate, [-3, 3, 0])
    assert np.allclose(script.poses["turn"]["base"][0], 0.0)


@pytest.mark.parametrize("text, message", [
    ("poses: {a: {}}", "needs 'handles' and 'poses'"),
    ("handles: {h: {box: [[1, 0, 0], [0, 1, 1]]}}\nposes: {a: {}}", "min < max"),
    ("handles: {h: {box: [[0, 0, 0], [1, 1, 1]]}}\nposes: {a: {g: {}}}", "unknown handle(s) g"),
    ("handles: {h: {box: [[0, 0, 0], [1, 1, 1]]}}\nposes: {a: {h: {rotate: [1, 2]}}}", "three numbers"),
    ("handles: [", "not valid YAML"),
    ("handles: {h: {vertices: [1.5]}}\nposes: {a: {}}", "vertex ids"),
    ("handles: {h: {points: [[1, 2]]}}\nposes: {a: {}}", "list of [x, y, z]"),
])
def test_a_bad_pose_script_is_refused_naming_the_file(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(InputError, match="bad.yaml") as info:
        read_pose_script(path)
    assert message in str(info.value)


def test_a_poser_carries_the_surface_rigidly_and_keeps_the_rigid_region(tmp_path):
    X, T = tet_grid((20, 2, 2), (10.0, 1.0, 1.0))
    V = X[::7] * 0.98 + 0.01  # points inside the bar, carried by it
    path = tmp_path / "s.yaml"
    path.write_text(SCRIPT)
    script = read_pose_script(path)
    regions = {n: region_tets(X, T, b) for n, (_, b) in script.handles.items()}
    rigid = {n: region_tets(X, T, b) for n, b in script.rigid.items()}
    poser = VolumetricPoser(V, X, T, regions, rigid)
    lifted = poser.pose({"tip": (np.zeros(3), np.zeros(3)), "base": (np.zeros(3), np.zeros(3))}, iterations=2)
    assert np.abs(lifted.positions - V).max() < 1e-12  # no move: the rest
    turned = poser.pose(script.poses["turn"], iterations=10)
    ends = np.unique(T[regions["tip"]])
    centre = X[ends].mean(axis=0)
    expected = centre + (X[ends] - centre) @ np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]).T + [-3, 3, 0]
    assert np.abs(turned.edit.X[ends] - expected).max() < 1e-12
    mid = np.unique(T[rigid["middle"]])
    d0 = np.linalg.norm(X[mid][:, None] - X[mid][None], axis=2)
    d1 = np.linalg.norm(turned.edit.X[mid][:, None] - turned.edit.X[mid][None], axis=2)
    assert np.abs(d1 - d0).max() < 1e-9


def test_the_stage_authors_the_demo_script_into_a_library(tmp_path):
    V, F, _ = demo.demo_library(around=16)
    write_mesh(tmp_path / "ref.obj", V, F)
    script = __import__("conftest").ROOT / "examples" / "demo-limb-volumetric.yaml"
    run_stage("volumetric_pose", "--mesh", tmp_path / "ref.obj", "--script", script, "--out", tmp_path / "lib",
              "--artifact", tmp_path / "a.h5", "--tet-vertices", 300)
    names = sorted(p.name for p in (tmp_path / "lib").iterdir())
    assert names == ["demo-limb-volumetric-reference.obj", "vol-bend.obj", "vol-fold.obj", "vol-twist.obj"]
    reference, F_ref = read_mesh(tmp_path / "lib" / "demo-limb-volumetric-reference.obj")
    assert np.array_equal(reference, V) and np.array_equal(F_ref, F)
    bent, F_bent = read_mesh(tmp_path / "lib" / "vol-bend.obj")
    assert np.array_equal(F_bent, F) and bent[:, 1].max() > 2.0  # the tip went up
    fold, _ = read_mesh(tmp_path / "lib" / "vol-fold.obj")
    assert intersecting_faces(self_intersecting_pairs(fold, F), len(F)).sum() > 0  # something for the repair
    with h5py.File(tmp_path / "a.h5", "r") as fh:
        assert fh.attrs["stage"] == "volumetric_pose" and fh["posed"].shape[0] == 3
        assert np.all(fh["shear"][()] < 0.5)
    (tmp_path / "far.yaml").write_text("handles: {h: {box: [[10, 10, 10], [11, 11, 11]]}}\nposes: {a: {}}\n")
    proc = run_stage("volumetric_pose", "--mesh", tmp_path / "ref.obj", "--script", tmp_path / "far.yaml",
                     "--out", tmp_path / "lib2", "--artifact", tmp_path / "b.h5", "--tet-vertices", 300, check=False)
    assert proc.returncode == 2 and "far.yaml" in proc.stderr and "no tet lies wholly in its box" in proc.stderr
    assert not (tmp_path / "b.h5").exists()


def test_point_handles_by_position_move_with_their_group(tmp_path):
    X, T = tet_grid((20, 2, 2), (10.0, 1.0, 1.0))
    path = tmp_path / "s.yaml"
    path.write_text("handles:\n  base: {box: [[-0.01, -1, -1], [0.51, 2, 2]]}\n"
                    "  markers: {points: [[9.7, 0.5, 0.5], [9.7, 0.2, 0.3], [9.2, 0.6, 0.7]]}\n"
                    "poses:\n  up: {markers: {rotate: [0, 90, 0], translate: [-1, 0, 4]}}\n")
    script = read_pose_script(path)
    kind, points = script.handles["markers"]
    assert kind == "points" and points.shape == (3, 3)
    poser = VolumetricPoser(X[::5], X, T, {"base": region_tets(X, T, script.handles["base"][1])},
                            points={"markers": points})
    posed = poser.pose(script.poses["up"], iterations=10)
    _, _, targets = poser.targets(script.poses["up"])
    from posefix.volumetric.embedding import barycentric_embedding, embedded_points
    assert np.abs(embedded_points(posed.edit.X, T, *barycentric_embedding(X, T, points)) - targets).max() < 1e-9
    assert np.linalg.norm(targets.mean(axis=0) - (points.mean(axis=0) + [-1, 0, 4])) < 1e-12
