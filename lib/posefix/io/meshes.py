"""Mesh files: names, validated reading exactly as stored, and format-preserving writing.

Meshes are read with ``trimesh.load(..., process=False)`` (and the format's ``LOAD_KWARGS``, e.g.
``maintain_order=True`` for OBJ) so vertex order and faces are exactly the file's. Every problem
is raised as :class:`~posefix.io.errors.InputError` naming the file and the problem in one
line. The formats themselves are in :mod:`posefix.io.formats`.
"""

import gzip
import io
import os
import re
from dataclasses import dataclass

import numpy as np

from posefix.io.errors import InputError, one_line
from posefix.io.files import atomic_write_bytes
from posefix.io.formats import FORMATS

MESH_SUFFIXES = "(.obj, .ply, .off, optionally .gz)"


@dataclass(frozen=True)
class MeshFile:
    """A mesh file of a pose library.

    Attributes
    ----------
    path : str
    name : str
        The file name without its mesh extensions (``lion-01`` for ``lion-01.obj.gz``).
    fmt : str
        ``obj``, ``ply`` or ``off``.
    gz : bool
        Whether the file is gzip-compressed.
    """

    path: str
    name: str
    fmt: str
    gz: bool

    @property
    def suffix(self):
        """Extension(s) of the file, e.g. ``.obj.gz``."""
        return f".{self.fmt}" + (".gz" if self.gz else "")


def mesh_file(path):
    """The :class:`MeshFile` for ``path``, or None when its extension is not a mesh format."""
    pattern = r"(.+)\.(" + "|".join(FORMATS) + r")(\.gz)?"
    m = re.fullmatch(pattern, os.path.basename(path), flags=re.IGNORECASE)
    if not m:
        return None
    return MeshFile(path=str(path), name=m.group(1), fmt=m.group(2).lower(), gz=m.group(3) is not None)


def _known(path):
    mf = mesh_file(path)
    if mf is None:
        raise InputError(path, f"unknown mesh format (expected {MESH_SUFFIXES[1:-1]})")
    return mf


def read_mesh(path):
    """Read a triangle mesh exactly as stored.

    Parameters
    ----------
    path : str or Path
        ``.obj``, ``.ply`` or ``.off``, optionally ``.gz``.

    Returns
    -------
    V : (n, 3) float64
    F : (m, 3) int64

    Raises
    ------
    InputError
        Unknown extension, unreadable or empty file, not a triangle mesh, non-finite
        coordinates, or face indices out of range.
    """
    mf = _known(path)
    fmt = FORMATS[mf.fmt]
    data = _read_bytes(mf)
    declared = fmt.declared_counts(data)
    fmt.check(path, data)
    import trimesh  # here, not above: 0.1-0.2 s of start-up that a stage reading no mesh file need not pay

    try:
        mesh = trimesh.load(io.BytesIO(data), file_type=mf.fmt, process=False, force="mesh", **fmt.LOAD_KWARGS)
        V = np.asarray(mesh.vertices, dtype=np.float64)
        F = np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3)
    except Exception as exc:  # trimesh raises many types for malformed files
        reason = one_line(exc)
        if re.search(r"out of bounds|outside the range", reason):
            raise InputError(path, f"a face has a vertex index out of range ({reason})") from None
        raise InputError(path, f"cannot be read as {mf.fmt.upper()}: {reason}") from None
    _check_mesh(path, V, F, declared)
    return V, F


def _read_bytes(mf):
    """The bytes of a :class:`MeshFile`, gunzipped when it is ``.gz``; InputError when there are none."""
    try:
        with open(mf.path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise InputError(mf.path, f"cannot be opened: {exc.strerror or exc}") from None
    if not data:
        raise InputError(mf.path, "empty file")
    if mf.gz:
        try:
            data = gzip.decompress(data)
        except (OSError, EOFError) as exc:
            raise InputError(mf.path, f"not a valid gzip file: {one_line(exc)}") from None
        if not data:
            raise InputError(mf.path, "empty file (after gunzip)")
    return data


def _check_mesh(path, V, F, declared):
    nv, nf = declared
    if len(V) == 0 and not nv:
        raise InputError(path, "no vertices")
    if len(F) == 0:  # (trimesh drops the vertices of a file without faces)
        raise InputError(path, f"no faces ({nv} vertices and no face: points, not a triangle mesh)" if nv else
                         "no faces")
    if nv is not None and nv != len(V):
        raise InputError(path, f"file declares {nv} vertices but {len(V)} were read")
    if nf is not None and nf != len(F):
        raise InputError(path, f"{nf} faces in the file became {len(F)} triangles: only triangle meshes are supported")
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        raise InputError(path, f"{bad.sum()} vertices have NaN or infinite coordinates (first: vertex {np.argmax(bad)})")
    out = (F < 0) | (F >= len(V))
    if out.any():
        f = int(np.argmax(out.any(axis=1)))
        raise InputError(path, f"face {f} has a vertex index out of range 0..{len(V) - 1}: {F[f].tolist()}")


def write_mesh(path, V, F, **options):
    """Write a triangle mesh in the format given by the extension of ``path``, atomically.

    Coordinates are written with 17 significant digits (text formats) or as float64 (binary
    PLY), so reading the file back gives exactly ``V`` and ``F``.

    Parameters
    ----------
    path : str or Path
        ``.obj``, ``.ply`` or ``.off``, optionally ``.gz``.
    V : (n, 3) float
    F : (m, 3) int
    **options
        Of the format's ``encode`` (PLY: ``kind``, ``binary_little_endian`` by default, or ``ascii``,
        ``binary_big_endian``).
    """
    mf = _known(path)
    data = FORMATS[mf.fmt].encode(np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64), **options)
    _write(mf, data)


def write_like(path, V, F, source):
    """Write new vertex positions in the exact format of the mesh file they came from.

    OBJ keeps the source's text but the vertex (and per-vertex normal) lines; PLY keeps its
    encoding; OFF is written plain (see the format modules' ``encode_like``).

    Parameters
    ----------
    path : str or Path
        Output file; must have the source's extension(s).
    V : (n, 3) float
    F : (m, 3) int
        The source's faces.
    source : str or Path
        The input mesh file.
    """
    src, dst = mesh_file(source), mesh_file(path)
    if dst is None or (dst.fmt, dst.gz) != (src.fmt, src.gz):
        raise InputError(path, f"must have the same format as {source} ({src.suffix})")
    V, F = np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)
    _write(dst, FORMATS[src.fmt].encode_like(_read_bytes(src), V, F))


def _write(mf, data):
    atomic_write_bytes(mf.path, gzip.compress(data, compresslevel=6, mtime=0) if mf.gz else data)
