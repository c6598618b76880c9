"""Wavefront OBJ: text, 1-based indices; a file written like a source keeps all but its vertex lines."""

import re

from posefix.mesh.geometry import vertex_normals
from posefix.pipeline.errors import InputError
from posefix.pipeline.formats.text import rows

LOAD_KWARGS = {"maintain_order": True}


def declared_counts(data):
    """Numbers of ``v`` and ``f`` lines, ``(nv, nf)``."""
    return len(re.findall(rb"(?m)^[ \t]*v[ \t]", data)), len(re.findall(rb"(?m)^[ \t]*f[ \t]", data))


def check(path, data):
    """OBJ indices start at 1; trimesh would silently renumber a 0, so reject it here."""
    for number, line in enumerate(data.splitlines(), 1):
        tokens = line.split()
        if tokens and tokens[0] == b"f" and any(t.split(b"/")[0] in (b"0", b"-0") for t in tokens[1:]):
            raise InputError(path, f"line {number}: face vertex index 0 (OBJ indices start at 1)")


def encode(V, F):
    """OBJ bytes of ``V`` (n, 3) float64 and ``F`` (m, 3) int64 (17 significant digits)."""
    return ("# written by posefix\n" + rows("v ", V, "%.17g %.17g %.17g") + rows("f ", F + 1, "%d %d %d")).encode()


def encode_like(source, V, F):
    """The OBJ text ``source`` (bytes) with new positions ``V`` (n, 3) float64, line by line.

    Only ``v`` lines get the new coordinates (extra values such as vertex colours are kept) and,
    when the source has one ``vn`` per vertex, the ``vn`` lines get recomputed area-weighted
    normals of ``V`` and ``F`` (m, 3) int64. Faces, texture coordinates, groups and materials stay
    byte-identical.
    """
    normals = vertex_normals(V, F)
    lines = source.splitlines(keepends=True)
    n_vn = sum(1 for line in lines if line.split()[:1] == [b"vn"])
    out, iv, ivn = [], 0, 0
    for line in lines:
        tokens = line.split()
        end = line[len(line.rstrip(b"\r\n")):]
        if tokens[:1] == [b"v"]:
            extra = b"".join(b" " + t for t in tokens[4:])
            line = (b"v %.17g %.17g %.17g" % tuple(V[iv])) + extra + end
            iv += 1
        elif tokens[:1] == [b"vn"] and n_vn == len(V):
            line = (b"vn %.9g %.9g %.9g" % tuple(normals[ivn])) + end
            ivn += 1
        out.append(line)
    return b"".join(out)

