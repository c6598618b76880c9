"""OFF: header counts (comments skipped), plain text written exactly."""

import numpy as np

from posefix.io.formats import off


def test_counts_from_a_commented_header():
    assert off.declared_counts(b"# made by hand\nOFF\n# counts\n4 2 0\n") == (4, 2)
    assert off.declared_counts(b"COFF 3 1 0\n") == (3, 1) and off.declared_counts(b"PLY") == (None, None)


def test_encode():
    text = off.encode(np.array([[0.5, 0, 1], [1, 1, 1], [0, 2, 0]]), np.array([[2, 1, 0]])).decode()
    assert text == "OFF\n3 1 0\n0.5 0 1\n1 1 1\n0 2 0\n3 2 1 0\n"
    assert off.encode_like(b"OFF\n# c\n", np.zeros((1, 3)), np.zeros((0, 3), dtype=int)) == b"OFF\n1 0 0\n0 0 0\n"
