"""Wavefront OBJ: text, 1-based indices; a file written like a source keeps all but its vertex lines."""

import re

from posefix.mesh.geometry import vertex_normals
from posefix.io.errors import InputError
from posefix.io.formats.text import rows

LOAD_KWARGS = {"maintain_order": True}


def declared_counts(data):
    """Numbers of ``v`` and ``f`` lines, ``(nv, nf)``."""
    return len(re.findall(rb"(?m)^[ \t]*v[ \t]", data)), len(re.findall(rb"(?m)^[ \t]*f[ \t]", data))


def check(path, data):
    """Problems trimesh would hide or word poorly, each as one :class:`InputError` naming the line.

    Binary data (garbage, or another format named .obj), a file of another mesh format, ``v`` lines
    with fewer than three coordinates or ``f`` lines with fewer than three vertices (a truncated file),
    coordinates that are not numbers, index 0 (OBJ indices start at 1; trimesh would renumber it) and indices past
    the last ``v`` line or, negative, before the first, reported as in the file.
    """
    if b"\x00" in data[:4096]:
        raise InputError(path, "binary data, not an OBJ text file")
    first = next((line.split()[0] for line in data.splitlines() if line.strip() and not line.lstrip().startswith(b"#")),
                 b"")
    if first.lower() in (b"ply", b"off", b"coff", b"noff", b"solid"):
        raise InputError(path, f"{first.decode().upper()} data in a .obj file (wrong extension?)")
    vertices = declared_counts(data)[0]
    if vertices == 0:
        raise InputError(path, "no vertex lines ('v x y z'): not an OBJ mesh")
    for number, line in enumerate(data.splitlines(), 1):
        tokens = line.split()
        if tokens[:1] == [b"v"] and len(tokens) < 4:
            raise InputError(path, f"line {number}: a vertex with {len(tokens) - 1} coordinates (truncated file?)")
        if tokens[:1] == [b"v"]:
            _check_coordinates(path, number, tokens[1:4])
        if tokens[:1] == [b"f"]:
            _check_face(path, number, tokens[1:], vertices)


def _check_coordinates(path, number, values):
    """One ``v`` line's x, y, z (bytes): numbers."""
    for value in values:
        try:
            float(value)
        except ValueError:
            raise InputError(path, f"line {number}: vertex coordinate {value.decode(errors='replace')!r} is not a "
                                   "number") from None


def _check_face(path, number, corners, vertices):
    """One ``f`` line: at least three corners, 1-based indices within the file's ``v`` lines (negative:
    relative, left to trimesh)."""
    if len(corners) < 3:
        raise InputError(path, f"line {number}: a face with {len(corners)} vertices (truncated file?)")
    for corner in corners:
        index = corner.split(b"/")[0]
        try:
            value = int(index)
        except ValueError:
            raise InputError(path, f"line {number}: face vertex index {index.decode(errors='replace')!r} is not "
                                   "an integer") from None
        if value == 0:
            raise InputError(path, f"line {number}: face vertex index 0 (OBJ indices start at 1)")
        if value < -vertices:
            raise InputError(path, f"line {number}: face vertex index {value} is out of range -{vertices}..-1 "
                                   "(a negative index counts back from the last vertex line before it)")
        if value > vertices:
            raise InputError(path, f"line {number}: face vertex index {value} is out of range 1..{vertices} "
                                   "(OBJ indices start at 1)")


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

