"""OFF: header counts (comments skipped), plain text written exactly."""

import numpy as np
import pytest

from conftest import icosphere
from posefix.io.errors import InputError
from posefix.io.formats import off
from posefix.io.meshes import read_mesh


def test_counts_from_a_commented_header():
    assert off.declared_counts(b"# made by hand\nOFF\n# counts\n4 2 0\n") == (4, 2)
    assert off.declared_counts(b"COFF 3 1 0\n") == (3, 1) and off.declared_counts(b"PLY") == (None, None)


def test_encode():
    text = off.encode(np.array([[0.5, 0, 1], [1, 1, 1], [0, 2, 0]]), np.array([[2, 1, 0]])).decode()
    assert text == "OFF\n3 1 0\n0.5 0 1\n1 1 1\n0 2 0\n3 2 1 0\n"
    assert off.encode_like(b"OFF\n# c\n", np.zeros((1, 3)), np.zeros((0, 3), dtype=int)) == b"OFF\n1 0 0\n0 0 0\n"


@pytest.mark.parametrize("declared", [167, 157])
def test_a_header_that_miscounts_the_vertices_is_named_as_the_cause(tmp_path, declared):
    """Issue 50: a header announcing 5 vertices more (or fewer) than the body's was reported as faces that became
    fewer triangles."""
    V, F = icosphere(2)  # 162 vertices, 320 faces
    text = off.encode(V, F).decode().replace("OFF\n162 320 0\n", f"OFF\n{declared} 320 0\n")
    (tmp_path / "a.off").write_text(text)
    with pytest.raises(InputError) as error:
        read_mesh(tmp_path / "a.off")
    assert str(error.value) == f"{tmp_path / 'a.off'}: the header declares {declared} vertices but the file has 162 " \
                               "vertex rows"
