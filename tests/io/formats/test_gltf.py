"""glTF containers: morph targets read as the specification says (sparse, normalized, interleaved) and written
back with only the repaired targets' displacements changed."""

import numpy as np
import pygltflib
import pytest

from conftest import icosphere
from containers import write_gltf
from posefix.io.containers import open_container
from posefix.io.formats.gltf import read_accessor


@pytest.fixture(scope="module")
def sphere():
    V, F = icosphere(1)
    return V, F, [V * 1.1, V + 0.1, V * 0.9]


def base_plus(V, P):
    """What a float32 base and float32 displacement give back: f32(V) + f32(P - f32(V)) in float64."""
    base = np.asarray(V, dtype=np.float32)
    return base.astype(np.float64) + (np.asarray(P, dtype=np.float32) - base).astype(np.float64)


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_morph_targets_dense_and_sparse_round_trip(tmp_path, sphere, suffix):
    V, F, poses = sphere
    moved = V.copy()
    moved[[2, 9]] += 0.2
    path = write_gltf(tmp_path / f"face{suffix}", V, [poses[0], moved, poses[2]], F, ["smile", "brow", "blink"],
                      sparse=(1,))
    box = open_container(path)
    assert list(box.members) == ["face-reference", "smile", "brow", "blink"] and box.mesh == "Body"
    assert np.array_equal(box.faces, F) and box.n == len(V)
    assert np.array_equal(box.points("brow"), base_plus(V, moved))
    repaired = {"brow": moved + 0.01, "smile": poses[0] - 0.02}
    (tmp_path / "out").mkdir()
    box.write(tmp_path / "out" / f"face{suffix}", repaired)
    back = open_container(tmp_path / "out" / f"face{suffix}")
    assert list(back.members) == list(box.members) and np.array_equal(back.faces, F)
    for name, X in repaired.items():
        np.testing.assert_allclose(back.points(name), X, rtol=0, atol=1e-6)
    assert np.array_equal(back.points("blink"), box.points("blink"))
    assert np.array_equal(back.points("face-reference"), box.points("face-reference"))
    gltf = pygltflib.GLTF2().load(str(tmp_path / "out" / f"face{suffix}"))
    assert gltf.meshes[0].extras["targetNames"] == ["smile", "brow", "blink"] and len(gltf.accessors) == 5
    assert gltf.accessors[3].sparse is None  # the sparse target became dense: the repair moved every point
    assert gltf.accessors[2].bufferView == 2  # the dense one was rewritten in place


def test_normalized_interleaved_and_sparse_accessors_are_decoded(tmp_path):
    values = np.array([[-32767, 0, 32767], [16384, -32768, 1]], dtype="<i2")
    stride = 8  # VEC3 of int16 interleaved with 2 bytes of padding
    data = b"".join(row.tobytes() + b"\0\0" for row in values) + np.array([1], "<u1").tobytes() + b"\0\0\0" \
        + np.array([[100, 200, 300]], "<i2").tobytes()
    gltf = pygltflib.GLTF2(
        bufferViews=[pygltflib.BufferView(buffer=0, byteOffset=0, byteLength=16, byteStride=stride),
                     pygltflib.BufferView(buffer=0, byteOffset=16, byteLength=1),
                     pygltflib.BufferView(buffer=0, byteOffset=20, byteLength=6)],
        accessors=[pygltflib.Accessor(bufferView=0, componentType=5122, normalized=True, count=2, type="VEC3"),
                   pygltflib.Accessor(bufferView=0, componentType=5122, count=2, type="VEC3", sparse=pygltflib.Sparse(
                       count=1, indices=pygltflib.AccessorSparseIndices(bufferView=1, componentType=5121),
                       values=pygltflib.AccessorSparseValues(bufferView=2)))])
    decoded = read_accessor("x.glb", gltf, [data], 0, 2)
    assert np.array_equal(decoded, [[-1, 0, 1], [16384 / 32767, -1, 1 / 32767]])  # max(c / 32767, -1)
    assert np.array_equal(read_accessor("x.glb", gltf, [data], 1, 2), [[-32767, 0, 32767], [100, 200, 300]])


def test_a_mesh_of_several_primitives_is_one_library_mesh(tmp_path, sphere):
    V, F, poses = sphere
    path = write_gltf(tmp_path / "body.glb", V, poses, F)
    gltf = pygltflib.GLTF2().load(str(path))
    mesh = gltf.meshes[0]
    mesh.primitives.append(pygltflib.Primitive(attributes=pygltflib.Attributes(POSITION=0), indices=1,
                                               targets=mesh.primitives[0].targets))
    gltf.save(str(path))
    box = open_container(path)
    assert box.n == 2 * len(V) and np.array_equal(box.faces, np.concatenate([F, F + len(V)]))
    assert np.array_equal(box.points("target-1"), np.concatenate([base_plus(V, poses[1])] * 2))


def test_a_primitive_that_a_target_does_not_move_is_written_back_moved(tmp_path, sphere):
    """A morph target with no POSITION in one primitive (that primitive stays at its base in the pose; issue 50:
    it ended in a TypeError on write) gets its own accessor when the repaired pose moves it."""
    V, F, poses = sphere
    path = write_gltf(tmp_path / "body.glb", V, poses, F)
    gltf = pygltflib.GLTF2().load(str(path))
    mesh = gltf.meshes[0]
    mesh.primitives.append(pygltflib.Primitive(attributes=pygltflib.Attributes(POSITION=0), indices=1,
                                               targets=[dict(t) for t in mesh.primitives[0].targets]))
    mesh.primitives[1].targets[1] = {}  # target-1 does not move the second primitive
    gltf.save(str(path))
    box = open_container(path)
    base = base_plus(V, V)
    assert np.array_equal(box.points("target-1"), np.concatenate([base_plus(V, poses[1]), base]))
    moved = np.concatenate([base_plus(V, poses[1]), base + 0.25])
    box.write(tmp_path / "out.glb", {"target-1": moved})
    back = open_container(tmp_path / "out.glb")
    np.testing.assert_allclose(back.points("target-1"), moved, rtol=0, atol=1e-6)
    assert np.array_equal(back.points("target-0"), box.points("target-0"))
