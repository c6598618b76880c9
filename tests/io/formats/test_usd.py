"""USD containers: frames and blend shapes read as written by usd-core, and written back with only the repaired
poses' positions changed (float32 in point3f[] and vector3f[])."""

import numpy as np
import pytest
from pxr import Usd, UsdGeom, UsdSkel

from conftest import icosphere
from containers import write_usd_blend_shapes, write_usd_frames
from posefix.io.containers import open_container


@pytest.fixture(scope="module")
def sphere():
    V, F = icosphere(1)
    return V, F, [V * 1.1, V + 0.1, V * 0.9]


def f32(X):
    """``X`` as the float32 a USD point3f[] holds, back in float64."""
    return np.asarray(X, dtype=np.float32).astype(np.float64)


@pytest.mark.parametrize("suffix", [".usda", ".usdc", ".usd"])
def test_frames_read_exactly_and_write_back_only_the_repaired_ones(tmp_path, sphere, suffix):
    V, F, poses = sphere
    box = open_container(write_usd_frames(tmp_path / f"walk{suffix}", V, poses, F))
    assert list(box.members) == ["walk-reference", "walk-1", "walk-2", "walk-3"] and box.n == len(V)
    assert np.array_equal(box.faces, F) and box.faces.dtype == np.int64
    for name, P in zip(["walk-1", "walk-2", "walk-3"], poses):
        assert np.array_equal(box.points(name), f32(P)) and box.points(name).dtype == np.float64
    repaired = poses[1] + 0.01 * np.sin(np.arange(len(V)))[:, None]
    (tmp_path / "out").mkdir()
    box.write(tmp_path / "out" / f"walk{suffix}", {"walk-2": repaired})
    back = open_container(tmp_path / "out" / f"walk{suffix}")
    assert list(back.members.items()) == list(box.members.items()) and back.mesh == box.mesh
    assert np.array_equal(back.points("walk-2"), f32(repaired))
    for name in ("walk-reference", "walk-1", "walk-3"):
        assert np.array_equal(back.points(name), box.points(name))
    stage = Usd.Stage.Open(str(tmp_path / "out" / f"walk{suffix}"))
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (1, 3)
    geom = UsdGeom.Mesh(stage.GetPrimAtPath("/Character/Body"))
    assert list(geom.GetFaceVertexIndicesAttr().Get()) == F.ravel().tolist()


def test_polygons_become_fans_and_are_written_back_as_polygons(tmp_path):
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 1.0]])
    quads = [[0, 1, 2, 3], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]
    box = open_container(write_usd_frames(tmp_path / "pyramid.usda", V, [V * 2], quads))
    assert box.faces.tolist() == [[0, 1, 2], [0, 2, 3], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]
    (tmp_path / "out").mkdir()
    box.write(tmp_path / "out" / "pyramid.usda", {"pyramid-1": V * 3})
    stage = Usd.Stage.Open(str(tmp_path / "out" / "pyramid.usda"))
    geom = UsdGeom.Mesh(stage.GetPrimAtPath("/Character/Body"))
    assert list(geom.GetFaceVertexCountsAttr().Get()) == [4, 3, 3, 3, 3]
    assert np.array_equal(np.asarray(geom.GetPointsAttr().Get(1)), (V * 3).astype(np.float32))


def test_blend_shapes_dense_and_sparse_are_offsets_from_the_base(tmp_path, sphere):
    V, F, poses = sphere
    moved = V.copy()
    moved[:5] += 0.3  # a sparse shape: five points
    path = write_usd_blend_shapes(tmp_path / "face.usdc", V, [poses[0], moved], F, ["smile", "brow"], sparse=(1,))
    box = open_container(path)
    assert list(box.members) == ["face-reference", "smile", "brow"] and not box.rebase
    assert np.abs(box.points("brow") - moved).max() < 1e-6 and np.array_equal(box.points("face-reference"), f32(V))
    repaired = box.points("brow")  # as unpacked: the points the repair leaves keep a zero offset
    repaired[[3, 20]] += 0.05  # the repair moves point 20 too: it joins the shape's points
    (tmp_path / "out").mkdir()
    box.write(tmp_path / "out" / "face.usdc", {"brow": repaired})
    back = open_container(tmp_path / "out" / "face.usdc")
    assert list(back.members) == list(box.members)
    np.testing.assert_allclose(back.points("brow"), repaired, rtol=0, atol=1e-6)
    assert np.array_equal(back.points("smile"), box.points("smile"))
    stage = Usd.Stage.Open(str(tmp_path / "out" / "face.usdc"))
    shape = UsdSkel.BlendShape(stage.GetPrimAtPath("/Character/Body/shape1"))
    assert list(shape.GetPointIndicesAttr().Get()) == [0, 1, 2, 3, 4, 20]


def test_a_usdz_package_is_read_and_written_as_a_package(tmp_path, sphere):
    from pxr import UsdUtils
    V, F, poses = sphere
    layer = write_usd_frames(tmp_path / "walk.usdc", V, poses, F)
    assert UsdUtils.CreateNewUsdzPackage(str(layer), str(tmp_path / "walk.usdz"))
    box = open_container(tmp_path / "walk.usdz")
    (tmp_path / "out").mkdir()
    box.write(tmp_path / "out" / "walk.usdz", {"walk-3": poses[2] * 1.5})
    assert (tmp_path / "out" / "walk.usdz").read_bytes()[:2] == b"PK"  # a zip archive
    assert np.array_equal(open_container(tmp_path / "out" / "walk.usdz").points("walk-3"), f32(poses[2] * 1.5))


def test_the_same_repair_writes_the_same_bytes(tmp_path, sphere):
    V, F, poses = sphere
    box = open_container(write_usd_frames(tmp_path / "walk.usdc", V, poses, F))
    for run in ("a", "b"):
        (tmp_path / run).mkdir()
        box.write(tmp_path / run / "walk.usdc", {"walk-1": poses[0] * 0.5})
    assert (tmp_path / "a" / "walk.usdc").read_bytes() == (tmp_path / "b" / "walk.usdc").read_bytes()


def test_pack_refuses_a_pose_whose_float32_rounding_makes_faces_intersect_and_writes_one_with_a_gap(tmp_path):
    """Stage pack reads the file back and runs the exact detector: the two triangles of ``float32_crossing`` apart
    in float64 but crossing once rounded are refused in one line naming the pose; pushed apart by the contact
    solver's keep_gap (as every contact repair ends), they are written and stay apart in the file."""
    from conftest import float32_crossing, run_stage
    from posefix.io.meshes import write_mesh
    from posefix.mesh.contact_solver import ContactSolver
    from posefix.mesh.intersections import self_intersecting_pairs
    V_ref, X, F = float32_crossing()
    path = write_usd_frames(tmp_path / "pair.usda", V_ref, [V_ref], F)
    (tmp_path / "repaired").mkdir()
    write_mesh(tmp_path / "repaired" / "pair-1.ply", X, F)
    args = ["--container", path, "--repaired", tmp_path / "repaired", "--poses", "pair-1"]
    (tmp_path / "out").mkdir()
    proc = run_stage("pack", *args, "--out", tmp_path / "out" / "pair.usda", check=False)
    assert proc.returncode != 0 and not any((tmp_path / "out").iterdir())
    assert proc.stderr.strip().splitlines()[-1].endswith(
        "out/pair.usda: mesh /Character/Body, frame 1: rounded to the file's float32, 2 faces intersect that do not in the "
        "repaired mesh"), proc.stderr
    Y, _ = ContactSolver(V_ref, F).keep_gap(X, np.ones(6, dtype=bool))
    write_mesh(tmp_path / "repaired" / "pair-1.ply", Y, F)
    run_stage("pack", *args, "--out", tmp_path / "out" / "pair.usda")
    assert len(self_intersecting_pairs(open_container(tmp_path / "out" / "pair.usda").points("pair-1"), F)) == 0
