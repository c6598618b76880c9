"""Text rows of the text formats."""

import numpy as np

from posefix.io.formats.text import rows


def test_rows():
    assert rows("v ", np.array([[1.0, 2.5, -0.0]]), "%.17g %.17g %.17g") == "v 1 2.5 -0\n"
    assert rows("3 ", np.array([[0, 1, 2], [2, 1, 0]]), "%d %d %d") == "3 0 1 2\n3 2 1 0\n"
