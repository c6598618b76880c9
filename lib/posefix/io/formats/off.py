"""Object File Format (OFF): text, a header with the counts, 0-based indices."""

import re

from posefix.io.formats.text import rows

LOAD_KWARGS = {}


def declared_counts(data):
    """Vertex and face counts of the OFF header, ``(nv, nf)``; None where the header has none."""
    tokens = re.sub(rb"#[^\n]*", b"", data[:4096]).split()
    if len(tokens) >= 3 and tokens[0].upper().endswith(b"OFF") and tokens[1].isdigit() and tokens[2].isdigit():
        return int(tokens[1]), int(tokens[2])
    return None, None


def check(path, data):
    """Nothing that trimesh would silently change."""


def encode(V, F):
    """OFF bytes of ``V`` (n, 3) float64 and ``F`` (m, 3) int64 (17 significant digits)."""
    return (f"OFF\n{len(V)} {len(F)} 0\n" + rows("", V, "%.17g %.17g %.17g") + rows("3 ", F, "%d %d %d")).encode()


def encode_like(source, V, F):
    """Plain OFF (:func:`encode`): comments and colours of ``source`` are not carried over."""
    return encode(V, F)
