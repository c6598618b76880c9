"""Object File Format (OFF): text, a header with the counts, 0-based indices."""

import re

from posefix.io.errors import InputError
from posefix.io.formats.text import rows

LOAD_KWARGS = {}


def declared_counts(data):
    """Vertex and face counts of the OFF header, ``(nv, nf)``; None where the header has none."""
    tokens = re.sub(rb"#[^\n]*", b"", data[:4096]).split()
    if len(tokens) >= 3 and tokens[0].upper().endswith(b"OFF") and tokens[1].isdigit() and tokens[2].isdigit():
        return int(tokens[1]), int(tokens[2])
    return None, None


def check(path, data):
    """A header whose vertex count is not the body's: trimesh would read the first face rows as vertices (or the
    last vertex rows as faces), and the problem would show as a face count. Checked where the vertex rows are plain
    (three numbers each: a face row has at least four)."""
    nv, _ = declared_counts(data)
    if nv is None:
        return
    lines = [line.split() for line in re.sub(rb"#[^\n]*", b"", data).splitlines() if line.strip()]
    body = lines[1 if len(lines[0]) >= 3 else 2:]  # after "OFF nv nf ne" on one line, or the counts on the next
    if not body or len(body[0]) != 3:
        return
    plain = next((k for k, row in enumerate(body) if len(row) != 3), len(body))
    if plain != nv:
        raise InputError(path, f"the header declares {nv} vertices but the file has {plain} vertex rows")


def encode(V, F):
    """OFF bytes of ``V`` (n, 3) float64 and ``F`` (m, 3) int64 (17 significant digits)."""
    return (f"OFF\n{len(V)} {len(F)} 0\n" + rows("", V, "%.17g %.17g %.17g") + rows("3 ", F, "%d %d %d")).encode()


def encode_like(source, V, F):
    """Plain OFF (:func:`encode`): comments and colours of ``source`` are not carried over."""
    return encode(V, F)
