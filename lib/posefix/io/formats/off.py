"""Object File Format (OFF): text, a header with the counts, 0-based indices."""

import re

from posefix.io.formats.text import check_vertex_rows, rows

LOAD_KWARGS = {}


def declared_counts(data):
    """Vertex and face counts of the OFF header, ``(nv, nf)``; None where the header has none."""
    tokens = _uncommented(data[:4096]).split()
    if len(tokens) >= 3 and tokens[0].upper().endswith(b"OFF") and tokens[1].isdigit() and tokens[2].isdigit():
        return int(tokens[1]), int(tokens[2])
    return None, None


def check(path, data):
    """A header whose vertex count is not the body's (:func:`~posefix.io.formats.text.check_vertex_rows`), where the
    vertex rows are plain (three numbers each; not COFF's colours)."""
    nv, _ = declared_counts(data)
    if nv is None:
        return
    lines = [line for line in _uncommented(data).splitlines() if line.strip()]
    body = lines[1 if len(lines[0].split()) >= 3 else 2:]  # after "OFF nv nf ne" on one line, or the counts next
    if body and len(body[0].split()) == 3:
        check_vertex_rows(path, b"\n".join(body), nv, 3)


def _uncommented(data):
    """OFF bytes without their ``#`` comments."""
    return re.sub(rb"#[^\n]*", b"", data)


def encode(V, F):
    """OFF bytes of ``V`` (n, 3) float64 and ``F`` (m, 3) int64 (17 significant digits)."""
    return (f"OFF\n{len(V)} {len(F)} 0\n" + rows("", V, "%.17g %.17g %.17g") + rows("3 ", F, "%d %d %d")).encode()


def encode_like(source, V, F):
    """Plain OFF (:func:`encode`): comments and colours of ``source`` are not carried over."""
    return encode(V, F)
