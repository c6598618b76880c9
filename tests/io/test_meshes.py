"""Mesh files: exact round trips in every format, vertex order kept, writing like the input file."""

import gzip

import numpy as np
import pytest

from conftest import icosphere, shared_library
from posefix.io.errors import InputError
from posefix.io.meshes import mesh_file, read_mesh, write_like, write_mesh


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".off", ".obj.gz", ".ply.gz", ".off.gz"])
@pytest.mark.parametrize("encoding", ["binary_little_endian", "ascii"])
def test_write_read_round_trip_is_exact(tmp_path, suffix, encoding):
    rng = np.random.default_rng(0)
    V, F = rng.normal(size=(30, 3)) * 1e3, rng.integers(0, 30, size=(40, 3))
    write_mesh(tmp_path / f"m{suffix}", V, F, **({"kind": encoding} if ".ply" in suffix else {}))
    V2, F2 = read_mesh(tmp_path / f"m{suffix}")
    assert np.array_equal(V, V2) and np.array_equal(F, F2)


def test_obj_vertex_order_survives_texture_seams(tmp_path):
    # a vertex used with two texture coordinates must not be split or reordered
    seams = "vt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nvt .5 .5\nf 1/1 2/2 3/3\nf 2/5 4/4 3/3\n"
    (tmp_path / "seam.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n" + seams)
    V, F = read_mesh(tmp_path / "seam.obj")
    assert V.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]
    assert F.tolist() == [[0, 1, 2], [1, 3, 2]]
    # trimesh drops unreferenced vertices of textured OBJ files: caught, never silently renumbered
    (tmp_path / "unused.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 9 9 9\n" + seams)
    with pytest.raises(InputError, match="file declares 5 vertices but 4 were read"):
        read_mesh(tmp_path / "unused.obj")


def test_write_like_keeps_obj_faces_normals_and_texture_lines(tmp_path):
    # the source has per-vertex normals, texture coordinates, a group and a material line
    src = tmp_path / "src.obj"
    src.write_text("# header\nmtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0 0.5 0.5 0.5\nv 0 0 1\n"
                   "vn 0 0 1\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\ng body\nusemtl skin\n"
                   "f 1/1/1 3/3/3 2/2/2\nf 1/1/1 2/2/2 4/1/4\nf 1/1/1 4/1/4 3/3/3\nf 2/2/2 3/3/3 4/1/4\n")
    V, F = read_mesh(src)
    V_new = V * 2.0 + 0.125
    write_like(tmp_path / "out.obj", V_new, F, src)
    V2, F2 = read_mesh(tmp_path / "out.obj")
    assert np.array_equal(V2, V_new) and np.array_equal(F2, F)
    a, b = src.read_text().splitlines(), (tmp_path / "out.obj").read_text().splitlines()
    assert len(a) == len(b)
    for x, y in zip(a, b):
        if x.split()[0] not in ("v", "vn"):
            assert x == y
    assert b[4].endswith(" 0.5 0.5 0.5")  # vertex colours kept
    normals = np.array([[float(t) for t in line.split()[1:]] for line in b if line.startswith("vn ")])
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    assert np.allclose(normals[0], -np.ones(3) / np.sqrt(3), atol=1e-8)  # corner at the origin, outward


def test_write_like_lion_pose_round_trip(tmp_path):
    src = shared_library("lion-poses") / "lion-01.obj"
    V, F = read_mesh(src)
    write_like(tmp_path / "lion-01.obj", V + 1e-3, F, src)
    V2, F2 = read_mesh(tmp_path / "lion-01.obj")
    assert np.array_equal(V2, V + 1e-3) and np.array_equal(F2, F)
    faces = [line for line in src.read_text().splitlines() if line.startswith("f ")]
    assert faces == [line for line in (tmp_path / "lion-01.obj").read_text().splitlines() if line.startswith("f ")]


@pytest.mark.parametrize("encoding", ["ascii", "binary_big_endian"])
def test_write_like_keeps_ply_encoding_and_gzip(tmp_path, encoding):
    V, F = icosphere(1)
    write_mesh(tmp_path / "src.ply.gz", V, F, kind=encoding)
    write_like(tmp_path / "out.ply.gz", V + 1.0, F, tmp_path / "src.ply.gz")
    assert f"format {encoding}".encode() in gzip.decompress((tmp_path / "out.ply.gz").read_bytes())[:200]
    V2, F2 = read_mesh(tmp_path / "out.ply.gz")
    assert np.array_equal(V2, V + 1.0) and np.array_equal(F2, F)
    with pytest.raises(InputError, match="same format"):
        write_like(tmp_path / "out.obj", V, F, tmp_path / "src.ply.gz")


def test_mesh_file_names_and_unknown_formats(tmp_path):
    mf = mesh_file("/x/lion-01.OBJ.gz")
    assert (mf.name, mf.fmt, mf.gz, mf.suffix) == ("lion-01", "obj", True, ".obj.gz")
    assert mesh_file("notes.txt") is None
    with pytest.raises(InputError, match="unknown mesh format"):
        write_mesh(tmp_path / "m.stl", *icosphere(1))
    with pytest.raises(InputError, match="must have the same format"):
        write_like(tmp_path / "m.ply", *icosphere(1), tmp_path / "m.obj")
