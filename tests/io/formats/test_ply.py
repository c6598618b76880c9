"""PLY: header counts, the encoding of a source, exact float64 in all three encodings."""

import io

import numpy as np
import pytest
import trimesh

from conftest import icosphere
from posefix.io.errors import InputError
from posefix.io.formats import ply
from posefix.io.meshes import read_mesh


@pytest.mark.parametrize("kind", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_encodings_read_back_exactly(kind):
    V = np.array([[0.1, 2.0, -3.0], [1e-300, 1.0, 5.0], [np.pi, 0.0, 1.0]])
    F = np.array([[0, 1, 2]])
    data = ply.encode(V, F, kind)
    assert ply.encoding(data) == kind and ply.declared_counts(data) == (3, 1)
    mesh = trimesh.load(io.BytesIO(data), file_type="ply", process=False)
    assert np.array_equal(mesh.vertices, V) and np.array_equal(mesh.faces, F)
    assert ply.encoding(ply.encode_like(data, V + 1.0, F)) == kind


def test_header_without_counts():
    assert ply.declared_counts(b"ply\nformat ascii 1.0\n") == (None, None)
    assert ply.encoding(b"garbage") == ply.DEFAULT_ENCODING


@pytest.mark.parametrize("declared", [167, 157])
def test_an_ascii_header_that_miscounts_the_vertices_is_named_as_the_cause(tmp_path, declared):
    """Issue 50: trimesh said "could not be read to its end due to unmatched data"."""
    V, F = icosphere(2)  # 162 vertices, 320 faces
    text = ply.encode(V, F, "ascii").decode().replace("element vertex 162\n", f"element vertex {declared}\n")
    (tmp_path / "a.ply").write_text(text)
    with pytest.raises(InputError) as error:
        read_mesh(tmp_path / "a.ply")
    assert str(error.value) == f"{tmp_path / 'a.ply'}: the header declares {declared} vertices but the file has 162 " \
                               "vertex rows"
