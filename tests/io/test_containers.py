"""Pose libraries in one USD or glTF file: triangles of polygons, pose names, the library a container makes, and a
one-line error (file, prim or target, problem) for every bad container."""

import numpy as np
import pygltflib
import pytest
from pxr import Usd, UsdGeom, Vt

from conftest import icosphere, run_stage
from containers import write_gltf, write_usd_blend_shapes, write_usd_frames
from posefix.io.containers import container_stem, fan_triangles, open_container, pose_names
from posefix.io.errors import InputError
from posefix.io.library import container_library


@pytest.fixture(scope="module")
def sphere():
    """An icosphere and three poses of it: (V (42, 3), F (80, 3), [three (42, 3)])."""
    V, F = icosphere(1)
    return V, F, [V * 1.1, V + 0.1, V * 0.9]


def test_fan_triangles_of_a_triangle_a_quad_and_a_pentagon():
    T = fan_triangles("x", [3, 4, 5], [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11], 12)
    assert T.tolist() == [[0, 1, 2], [3, 4, 5], [3, 5, 6], [7, 8, 9], [7, 9, 10], [7, 10, 11]]


def test_pose_names_replace_what_a_file_name_cannot_carry():
    assert pose_names("x", ["jaw/open", "{a}", "smile", ".hidden"]) == ["jaw_open", "_a_", "smile", "hidden"]
    assert container_stem("/a/b/character.anim.usdz") == "character.anim"
    with pytest.raises(InputError, match="two poses would both be named 'jaw_open' \\('jaw open' and 'jaw/open'\\)"):
        pose_names("x.glb", ["jaw open", "jaw/open"])
    with pytest.raises(InputError, match="named 'x-reference' \\(the rest pose and 'x-reference'\\)"):
        pose_names("x.glb", ["smile", "x-reference"], rest="x-reference")


def test_a_frame_library_takes_the_rest_pose_as_reference_and_names_frames_in_time_order(tmp_path, sphere):
    V, F, poses = sphere
    path = write_usd_frames(tmp_path / "walk.usda", V, poses * 4, F, first=1)  # frames 1..12: two digits
    library = container_library(path, tmp_path / "poses")
    assert library.name == "walk" and library.reference.name == "walk-reference" and library.mesh == "/Character/Body"
    assert [p.name for p in library.poses] == [f"walk-{k:02d}" for k in range(1, 13)]
    assert library.poses[0].path == f"{tmp_path / 'poses'}/walk-01.ply" and library.container == str(path)
    chosen = container_library(path, tmp_path / "poses", reference="3", poses=["walk-01", "walk-12"])
    assert chosen.reference.name == "walk-03" and [p.name for p in chosen.poses] == ["walk-01", "walk-12"]
    without_rest = write_usd_frames(tmp_path / "run.usdc", V, poses, F, rest=False, first=0)
    library = container_library(without_rest, tmp_path / "poses")
    assert library.reference.name == "run-0" and [p.name for p in library.poses] == ["run-1", "run-2"]


def test_blend_shapes_and_morph_targets_are_poses_of_their_base(tmp_path, sphere):
    V, F, poses = sphere
    for path in (write_usd_blend_shapes(tmp_path / "face.usda", V, poses, F, ["smile", "jaw open", "blink"]),
                 write_gltf(tmp_path / "face.glb", V, poses, F, ["smile", "jaw open", "blink"])):
        library = container_library(path, tmp_path / "poses")
        assert library.reference.name == "face-reference"
        assert [p.name for p in library.poses] == ["smile", "jaw_open", "blink"]
        box = open_container(path)
        for name, P in zip(["smile", "jaw_open", "blink"], poses):
            np.testing.assert_allclose(box.points(name), P, atol=1e-6)
        with pytest.raises(InputError, match="the reference of blend shapes and morph targets is the base"):
            container_library(path, tmp_path / "poses", reference="smile")


def _one_line(exc_info, path, *phrases):
    text = str(exc_info.value)
    assert "\n" not in text and text.startswith(str(path)), text
    for phrase in phrases:
        assert phrase in text, text
    return text


def test_usd_without_a_mesh_without_poses_or_with_several_meshes(tmp_path, sphere):
    V, F, poses = sphere
    empty = tmp_path / "empty.usda"
    stage = Usd.Stage.CreateNew(str(empty))
    stage.GetRootLayer().Save()
    with pytest.raises(InputError) as exc:
        open_container(empty)
    _one_line(exc, empty, "no mesh (UsdGeom.Mesh prim) in the file")
    still = write_usd_frames(tmp_path / "still.usda", V, [], F)
    with pytest.raises(InputError) as exc:
        open_container(still)
    _one_line(exc, still, "mesh /Character/Body: its points have no time samples and it has no blend shapes")
    two = write_usd_frames(tmp_path / "two.usda", V, poses, F)
    stage = Usd.Stage.Open(str(two))
    UsdGeom.Mesh.Define(stage, "/Character/Eyes")
    stage.GetRootLayer().Save()
    with pytest.raises(InputError) as exc:
        open_container(two)
    _one_line(exc, two, "2 meshes (/Character/Body, /Character/Eyes): choose one with the config's mesh")
    with pytest.raises(InputError) as exc:
        open_container(two, "/Character/Head")
    _one_line(exc, two, "no mesh prim /Character/Head (meshes: /Character/Body, /Character/Eyes)")
    assert open_container(two, "/Character/Body").mesh == "/Character/Body"


def test_usd_frames_with_a_different_point_count_or_nan(tmp_path, sphere):
    V, F, poses = sphere
    bad = [poses[0], poses[1][:-2], poses[2].copy()]
    bad[2][5, 1] = np.nan
    path = write_usd_frames(tmp_path / "bad.usdc", V, bad, F)
    box = open_container(path)
    box.points("bad-1")
    with pytest.raises(InputError) as exc:
        box.points("bad-2")
    _one_line(exc, path, "mesh /Character/Body, frame 2: 40 points, the mesh has 42")
    with pytest.raises(InputError) as exc:
        box.points("bad-3")
    _one_line(exc, path, "frame 3: 1 points are NaN or infinite (first: point 5)")


def test_usd_faces_that_cannot_be_triangulated_or_that_change_over_time(tmp_path, sphere):
    V, F, poses = sphere
    faces = [list(f) for f in F[:-1]] + [[0, 1]]
    path = write_usd_frames(tmp_path / "line.usda", V, poses, faces)
    with pytest.raises(InputError) as exc:
        open_container(path)
    _one_line(exc, path, "face 79 has 2 corners: not a polygon, cannot be triangulated")
    moving = write_usd_frames(tmp_path / "moving.usda", V, poses, F)
    stage = Usd.Stage.Open(str(moving))
    counts = UsdGeom.Mesh(stage.GetPrimAtPath("/Character/Body")).GetFaceVertexCountsAttr()
    for t in (1, 2):
        counts.Set(Vt.IntArray([3] * len(F)), t)
    stage.GetRootLayer().Save()
    with pytest.raises(InputError) as exc:
        open_container(moving)
    _one_line(exc, moving, "faceVertexCounts is time-sampled: the faces change between frames")


def test_truncated_or_foreign_files(tmp_path, sphere):
    V, F, poses = sphere
    usda = write_usd_frames(tmp_path / "cut.usda", V, poses, F)
    usda.write_bytes(usda.read_bytes()[:2000])
    with pytest.raises(InputError) as exc:
        open_container(usda)
    _one_line(exc, usda, "cannot be read as USD: ")
    glb = write_gltf(tmp_path / "cut.glb", V, poses, F)
    glb.write_bytes(glb.read_bytes()[:-500])
    with pytest.raises(InputError) as exc:
        open_container(glb).points("target-2")
    _one_line(exc, glb, "(truncated file?)")
    text = tmp_path / "text.glb"
    text.write_text("solid cube\nendsolid\n")
    with pytest.raises(InputError) as exc:
        open_container(text)
    _one_line(exc, text, "cannot be read as glTF: ")
    with pytest.raises(InputError) as exc:
        open_container(tmp_path / "missing.usd")
    _one_line(exc, tmp_path / "missing.usd", "no such file")


def test_gltf_without_morph_targets_with_nan_or_with_a_compression_it_cannot_read(tmp_path, sphere):
    V, F, poses = sphere
    plain = write_gltf(tmp_path / "plain.glb", V, [], F)
    with pytest.raises(InputError) as exc:
        open_container(plain)
    _one_line(exc, plain, "no mesh with morph targets (meshes: Body): no poses")
    bad = poses[1].copy()
    bad[7] = np.inf
    path = write_gltf(tmp_path / "nan.gltf", V, [poses[0], bad], F, ["smile", "frown"])
    with pytest.raises(InputError) as exc:
        open_container(path).points("frown")
    _one_line(exc, path, "mesh Body, morph target 1 (frown): 1 points are NaN or infinite (first: point 7)")
    gltf = pygltflib.GLTF2().load(str(write_gltf(tmp_path / "draco.glb", V, poses, F)))
    gltf.extensionsRequired = ["KHR_draco_mesh_compression"]
    gltf.save(str(tmp_path / "draco.glb"))
    with pytest.raises(InputError) as exc:
        open_container(tmp_path / "draco.glb")
    _one_line(exc, tmp_path / "draco.glb", "needs the glTF extension(s) KHR_draco_mesh_compression")


def test_a_bad_frame_fails_its_unpack_stage_in_one_line_naming_the_file_and_frame(tmp_path, sphere):
    V, F, poses = sphere
    bad = poses[1].copy()
    bad[3] = np.nan
    path = write_usd_frames(tmp_path / "walk.usda", V, [poses[0], bad], F)
    ok = run_stage("unpack", "--container", path, "--pose", "walk-1", "--out", tmp_path / "walk-1.ply")
    assert ok.returncode == 0 and (tmp_path / "walk-1.ply").is_file()
    proc = run_stage("unpack", "--container", path, "--pose", "walk-2", "--out", tmp_path / "walk-2.ply", check=False)
    assert proc.returncode == 2 and not (tmp_path / "walk-2.ply").exists()
    assert proc.stderr.strip() == (f"posefix unpack: error: {path}: mesh /Character/Body, frame 2: 1 points are NaN "
                                   "or infinite (first: point 3)")
