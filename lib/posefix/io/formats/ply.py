"""Stanford PLY: ascii or binary (either endianness); written with float64 coordinates."""

import re

import numpy as np

from posefix.io.errors import InputError
from posefix.io.formats.text import check_vertex_rows, rows

LOAD_KWARGS = {}
DEFAULT_ENCODING = "binary_little_endian"
_HEADER = ("ply\nformat {} 1.0\ncomment written by posefix\nelement vertex {}\n"
           "property double x\nproperty double y\nproperty double z\n"
           "element face {}\nproperty list uchar int vertex_indices\nend_header\n")


def declared_counts(data):
    """Vertex and face counts of the PLY header, ``(nv, nf)``; None where the header has none."""
    header = data[: data.find(b"end_header")] if b"end_header" in data else b""
    nv = re.search(rb"element\s+vertex\s+(\d+)", header)
    nf = re.search(rb"element\s+face\s+(\d+)", header)
    return (int(nv.group(1)) if nv else None, int(nf.group(1)) if nf else None)


def check(path, data):
    """A header without its end (trimesh: "list index out of range"), or an ascii header whose vertex count is not
    the body's (:func:`~posefix.io.formats.text.check_vertex_rows`;
    trimesh reported "unmatched data"), where the vertex element comes first and its rows can be told from face
    rows (scalar properties, not four)."""
    end = data.find(b"end_header")
    if end < 0 and data[:3] == b"ply":
        raise InputError(path, "the PLY header has no end_header line (a truncated file?)")
    if end < 0 or encoding(data) != "ascii":
        return
    first = re.search(rb"element\s+(\w+)\s+(\d+)\s*\n((?:\s*property[^\n]*\n)*)", data[:end + 1])
    if first is None or first.group(1) != b"vertex" or b"list" in first.group(3):
        return
    width = first.group(3).count(b"property")
    if width != 4:
        check_vertex_rows(path, data[data.find(b"\n", end) + 1:], int(first.group(2)), width)


def encoding(data):
    """The ``format`` of a PLY file's header (``ascii``, ``binary_little_endian`` or ``binary_big_endian``)."""
    m = re.search(rb"format\s+(\w+)", data[:512])
    return m.group(1).decode() if m else DEFAULT_ENCODING


def encode_like(source, V, F):
    """PLY bytes in the encoding of ``source`` (bytes of a PLY file); its other vertex properties are
    not carried over."""
    return encode(V, F, encoding(source))


def encode(V, F, kind=DEFAULT_ENCODING):
    """PLY bytes of ``V`` (n, 3) float64 and ``F`` (m, 3) int64 with float64 coordinates; ``kind``
    ``ascii``, ``binary_little_endian`` or ``binary_big_endian``."""
    if kind == "ascii":
        return (_HEADER.format("ascii", len(V), len(F)) + rows("", V, "%.17g %.17g %.17g")
                + rows("3 ", F, "%d %d %d")).encode()
    order = ">" if kind == "binary_big_endian" else "<"
    faces = np.zeros(len(F), dtype=[("n", "u1"), ("v", f"{order}i4", 3)])
    faces["n"], faces["v"] = 3, F
    return _HEADER.format(kind, len(V), len(F)).encode() + V.astype(f"{order}f8").tobytes() + faces.tobytes()
