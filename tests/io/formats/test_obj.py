"""OBJ: announced counts, index 0 rejected, written exactly, rewritten like the source."""

import numpy as np
import pytest

from posefix.io.errors import InputError
from posefix.io.formats import obj

SOURCE = b"# c\nv 0 0 0\nv 1 0 0 0.2 0.2 0.2\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\r\n"


def test_counts_and_index_zero():
    assert obj.declared_counts(SOURCE) == (3, 1)
    obj.check("m.obj", SOURCE)
    with pytest.raises(InputError, match="line 2: face vertex index 0"):
        obj.check("m.obj", b"v 0 0 0\nf 0 1 2\n")


def test_encode_writes_17_digits_and_one_based_faces():
    text = obj.encode(np.array([[0.1, 1.0, -2.5]]), np.array([[0, 0, 0]])).decode()
    assert "v 0.10000000000000001 1 -2.5\n" in text and "f 1 1 1\n" in text


def test_encode_like_changes_only_vertex_lines():
    V = np.array([[1.0, 0, 0], [2.0, 0, 0], [1.0, 1, 0]])
    out = obj.encode_like(SOURCE, V, np.array([[0, 1, 2]])).split(b"\n")
    assert out[1] == b"v 1 0 0" and out[2] == b"v 2 0 0 0.2 0.2 0.2" and out[-2] == b"f 1/1 2/1 3/1\r"
    assert out[0] == b"# c" and out[4] == b"vt 0 0"
