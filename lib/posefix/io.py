"""Pose libraries on disk: discovery, validated mesh reading, and format-preserving writing.

A pose library is a folder of triangle meshes (``.obj``, ``.ply``, ``.off``, each optionally
``.gz``) that share one face array. Meshes are read with ``trimesh.load(..., process=False)``
(and ``maintain_order=True`` for OBJ) so vertex order and faces are exactly the file's. Every
problem is raised as :class:`InputError` naming the file and the problem in one line.
"""

import csv
import gzip
import hashlib
import io
import os
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from posefix.geometry import bbox_diagonal, face_areas, vertex_normals

FORMATS = ("obj", "ply", "off")
DEGENERATE_AREA_REL = 1e-14
"""Reference faces with area below this times the squared bbox diagonal count as zero-area."""


class InputError(Exception):
    """A problem with user input, reported as ``<path>: <problem>``."""

    def __init__(self, path, problem):
        super().__init__(f"{path}: {problem}")
        self.path, self.problem = str(path), problem


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


@dataclass(frozen=True)
class Library:
    """A pose library: one reference and the target poses to repair, in name order."""

    folder: str
    name: str
    reference: MeshFile
    poses: tuple

    def pose(self, name):
        """The :class:`MeshFile` of the pose called ``name``."""
        for p in self.poses:
            if p.name == name:
                return p
        raise KeyError(name)


def mesh_file(path):
    """The :class:`MeshFile` for ``path``, or None when its extension is not a mesh format."""
    m = re.fullmatch(r"(.+)\.(obj|ply|off)(\.gz)?", os.path.basename(path), flags=re.IGNORECASE)
    if not m:
        return None
    return MeshFile(path=str(path), name=m.group(1), fmt=m.group(2).lower(), gz=m.group(3) is not None)


def discover_library(folder, reference=None, poses=None, name=None):
    """Find the reference and target poses in a folder.

    Parameters
    ----------
    folder : str or Path
    reference : str, optional
        File name or pose name of the reference; default: the one mesh whose name ends in
        ``reference`` (e.g. ``lion-reference.obj``).
    poses : list of str, optional
        Names (or file names) of the target poses to use; default: every other mesh.
    name : str, optional
        Library name; default: the folder's name.

    Raises
    ------
    InputError
        Missing folder, no meshes, no or several reference candidates, unknown names,
        two files with the same pose name, or no target pose.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(folder, "not a folder")
    files = [mesh_file(p) for p in sorted(folder.iterdir()) if p.is_file() or p.is_symlink()]
    files = [f for f in files if f is not None]
    if not files:
        raise InputError(folder, "no mesh files (.obj, .ply, .off, optionally .gz)")
    by_name = {}
    for f in files:
        if f.name in by_name:
            raise InputError(f.path, f"same pose name '{f.name}' as {os.path.basename(by_name[f.name].path)}")
        by_name[f.name] = f
    ref = _pick_reference(folder, files, by_name, reference)
    if poses:
        missing = [p for p in poses if _lookup(by_name, p) is None]
        if missing:
            raise InputError(folder, f"pose(s) not found: {', '.join(missing)}")
        chosen = [_lookup(by_name, p) for p in poses]
    else:
        chosen = files
    chosen = tuple(sorted({f.name: f for f in chosen if f.name != ref.name}.values(), key=lambda f: f.name))
    if not chosen:
        raise InputError(folder, "no target poses besides the reference")
    return Library(folder=str(folder), name=name or folder.resolve().name, reference=ref, poses=chosen)


def _lookup(by_name, key):
    return by_name.get(key) or next((f for f in by_name.values() if os.path.basename(f.path) == key), None)


def _pick_reference(folder, files, by_name, reference):
    if reference:
        ref = _lookup(by_name, reference)
        if ref is None:
            raise InputError(folder, f"reference '{reference}' not found")
        return ref
    candidates = [f for f in files if f.name.lower().endswith("reference")]
    if not candidates:
        raise InputError(folder, "no reference found: no mesh name ends in 'reference'; "
                                 "set 'reference' in the config")
    if len(candidates) > 1:
        names = ", ".join(os.path.basename(f.path) for f in candidates)
        raise InputError(folder, f"several reference candidates ({names}); set 'reference' in the config")
    return candidates[0]


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
    mf = mesh_file(path)
    if mf is None:
        raise InputError(path, "unknown mesh format (expected .obj, .ply, .off, optionally .gz)")
    data = _read_bytes(mf)
    declared = _declared_counts(data, mf.fmt)
    if mf.fmt == "obj":
        _check_obj_indices(path, data)
    try:
        kwargs = {"maintain_order": True} if mf.fmt == "obj" else {}
        mesh = trimesh.load(io.BytesIO(data), file_type=mf.fmt, process=False, force="mesh", **kwargs)
        V = np.asarray(mesh.vertices, dtype=np.float64)
        F = np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3)
    except Exception as exc:  # trimesh raises many types for malformed files
        reason = _one_line(exc)
        if re.search(r"out of bounds|outside the range", reason):
            raise InputError(path, f"a face has a vertex index out of range ({reason})") from None
        raise InputError(path, f"cannot be read as {mf.fmt.upper()}: {reason}") from None
    _check_mesh(path, V, F, declared)
    return V, F


def _read_bytes(mf):
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
            raise InputError(mf.path, f"not a valid gzip file: {_one_line(exc)}") from None
        if not data:
            raise InputError(mf.path, "empty file (after gunzip)")
    return data


def _declared_counts(data, fmt):
    """Vertex and face counts announced by the file itself, ``(nv, nf)``; None where unknown."""
    if fmt == "obj":
        return (len(re.findall(rb"(?m)^[ \t]*v[ \t]", data)), len(re.findall(rb"(?m)^[ \t]*f[ \t]", data)))
    if fmt == "off":
        tokens = re.sub(rb"#[^\n]*", b"", data[:4096]).split()
        if len(tokens) >= 3 and tokens[0].upper().endswith(b"OFF") and tokens[1].isdigit() and tokens[2].isdigit():
            return int(tokens[1]), int(tokens[2])
        return None, None
    header = data[: data.find(b"end_header")] if b"end_header" in data else b""
    nv = re.search(rb"element\s+vertex\s+(\d+)", header)
    nf = re.search(rb"element\s+face\s+(\d+)", header)
    return (int(nv.group(1)) if nv else None, int(nf.group(1)) if nf else None)


def _check_obj_indices(path, data):
    """OBJ indices start at 1; trimesh would silently renumber a 0, so reject it here."""
    for number, line in enumerate(data.splitlines(), 1):
        tokens = line.split()
        if tokens and tokens[0] == b"f" and any(t.split(b"/")[0] in (b"0", b"-0") for t in tokens[1:]):
            raise InputError(path, f"line {number}: face vertex index 0 (OBJ indices start at 1)")


def _check_mesh(path, V, F, declared):
    if len(V) == 0:
        raise InputError(path, "no vertices")
    if len(F) == 0:
        raise InputError(path, "no faces")
    nv, nf = declared
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


def check_reference(path, V, F):
    """Raise :class:`InputError` when the reference has degenerate or zero-area faces."""
    repeated = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
    if repeated.any():
        f = int(np.argmax(repeated))
        raise InputError(path, f"reference has {repeated.sum()} degenerate faces repeating a vertex (first: face {f} {F[f].tolist()})")
    d = bbox_diagonal(V)
    tiny = face_areas(V, F) <= DEGENERATE_AREA_REL * d * d
    if tiny.any():
        f = int(np.argmax(tiny))
        raise InputError(path, f"reference has {tiny.sum()} zero-area faces (first: face {f})")


def check_pose(path, V, F, V_ref, F_ref):
    """Raise :class:`InputError` unless a pose matches the reference's vertex count and faces."""
    if len(V) != len(V_ref):
        raise InputError(path, f"{len(V)} vertices, the reference has {len(V_ref)}")
    if F.shape != F_ref.shape:
        raise InputError(path, f"{len(F)} faces, the reference has {len(F_ref)}")
    differ = np.any(F != F_ref, axis=1)
    if differ.any():
        f = int(np.argmax(differ))
        raise InputError(path, f"face array differs from the reference ({differ.sum()} faces; first: face {f} "
                               f"{F[f].tolist()} vs {F_ref[f].tolist()})")


def read_reference(path):
    """Read and validate a reference mesh: (V (n, 3) float64, F (m, 3) int64)."""
    V, F = read_mesh(path)
    check_reference(path, V, F)
    return V, F


def read_pose(path, V_ref, F_ref):
    """Read a target pose and check it against the reference; returns its (n, 3) vertices."""
    V, F = read_mesh(path)
    check_pose(path, V, F, V_ref, F_ref)
    return V


def read_pose_pair(reference_path, target_path):
    """Read and validate a reference and one target pose.

    Returns
    -------
    V_ref, V_tgt : (n, 3) float64
    F : (m, 3) int64
    """
    V_ref, F = read_reference(reference_path)
    return V_ref, read_pose(target_path, V_ref, F), F


def write_mesh(path, V, F, ply_encoding="binary_little_endian"):
    """Write a triangle mesh in the format given by the extension of ``path``, atomically.

    Coordinates are written with 17 significant digits (text formats) or as float64 (binary
    PLY), so reading the file back gives exactly ``V`` and ``F``.

    Parameters
    ----------
    path : str or Path
        ``.obj``, ``.ply`` or ``.off``, optionally ``.gz``.
    V : (n, 3) float
    F : (m, 3) int
    ply_encoding : str
        ``binary_little_endian`` or ``ascii`` (PLY only).
    """
    mf = mesh_file(path)
    if mf is None:
        raise InputError(path, "unknown mesh format (expected .obj, .ply, .off, optionally .gz)")
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    data = {"obj": _obj_bytes, "off": _off_bytes, "ply": _ply_bytes}[mf.fmt](V, F, ply_encoding)
    if mf.gz:
        data = gzip.compress(data, compresslevel=6, mtime=0)
    atomic_write_bytes(path, data)


def write_like(path, V, F, source):
    """Write new vertex positions in the exact format of the mesh file they came from.

    * OBJ: the source text is copied line by line; only ``v`` lines get the new coordinates (extra
      values such as vertex colours are kept) and, when the source has one ``vn`` per vertex, the
      ``vn`` lines get recomputed area-weighted normals. Faces, texture coordinates, groups and
      materials stay byte-identical.
    * PLY: same encoding as the source (ascii or binary, endianness), float64 coordinates; other
      vertex properties are not carried over.
    * OFF: plain OFF.

    Parameters
    ----------
    path : str or Path
        Output file; must have the source's extension(s).
    V : (n, 3) float
    F : (m, 3) int
        The source's faces (only used for PLY/OFF and the normals).
    source : str or Path
        The input mesh file.
    """
    src, dst = mesh_file(source), mesh_file(path)
    if dst is None or (dst.fmt, dst.gz) != (src.fmt, src.gz):
        raise InputError(path, f"must have the same format as {source} ({src.suffix})")
    if src.fmt != "obj":
        head = _read_bytes(src)[:512]
        m = re.search(rb"format\s+(\w+)", head) if src.fmt == "ply" else None
        write_mesh(path, V, F, ply_encoding=m.group(1).decode() if m else "binary_little_endian")
        return
    data = _obj_like(_read_bytes(src), np.asarray(V, dtype=np.float64), vertex_normals(V, F))
    atomic_write_bytes(path, gzip.compress(data, compresslevel=6, mtime=0) if src.gz else data)


def _obj_like(data, V, normals):
    lines = data.splitlines(keepends=True)
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


def atomic_write_bytes(path, data):
    """Write ``data`` to a temporary file next to ``path`` and rename it into place."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        publish(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def publish(tmp, path):
    """Give a finished temporary file the usual permissions (0666 minus umask), rename it to ``path``."""
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    os.replace(tmp, path)


def write_figure(path, fig):
    """Write a matplotlib ``Figure`` as PNG, atomically (same bytes for the same figure)."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", metadata={"Software": None})
    atomic_write_bytes(path, buffer.getvalue())


def benchmark_seconds(folder, stage):
    """Wall seconds from a Snakemake benchmark file ``folder/<stage>*.tsv`` (column ``s``), None when absent."""
    files = sorted(Path(folder).glob(f"{stage}*.tsv"))
    if not files:
        return None
    with open(files[0]) as fh:
        return float(next(csv.DictReader(fh, delimiter="\t"))["s"])


def file_sha256(path):
    """Hex sha256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _fmt_rows(prefix, A, fmt):
    return "".join(prefix + (fmt % tuple(row)) + "\n" for row in A.tolist())


def _obj_bytes(V, F, _):
    text = "# written by posefix\n" + _fmt_rows("v ", V, "%.17g %.17g %.17g") + _fmt_rows("f ", F + 1, "%d %d %d")
    return text.encode()


def _off_bytes(V, F, _):
    text = f"OFF\n{len(V)} {len(F)} 0\n" + _fmt_rows("", V, "%.17g %.17g %.17g") + _fmt_rows("3 ", F, "%d %d %d")
    return text.encode()


def _ply_bytes(V, F, encoding):
    header = ("ply\nformat {} 1.0\ncomment written by posefix\nelement vertex {}\n"
              "property double x\nproperty double y\nproperty double z\n"
              "element face {}\nproperty list uchar int vertex_indices\nend_header\n")
    if encoding == "ascii":
        return (header.format("ascii", len(V), len(F)) + _fmt_rows("", V, "%.17g %.17g %.17g")
                + _fmt_rows("3 ", F, "%d %d %d")).encode()
    order = ">" if encoding == "binary_big_endian" else "<"
    faces = np.zeros(len(F), dtype=[("n", "u1"), ("v", f"{order}i4", 3)])
    faces["n"], faces["v"] = 3, F
    return (header.format(encoding, len(V), len(F)).encode() + V.astype(f"{order}f8").tobytes()
            + faces.tobytes())


def _one_line(exc):
    text = str(exc).strip().splitlines()
    return (text[0] if text else type(exc).__name__)[:200]


def read_vertex_ids(path):
    """Read vertex ids from a text file: integers separated by whitespace or commas, ``#`` comments.

    Returns
    -------
    (k,) int64
    """
    try:
        with open(path) as fh:
            text = re.sub(r"#[^\n]*", "", fh.read())
    except OSError as exc:
        raise InputError(path, f"cannot be opened: {exc.strerror or exc}") from None
    tokens = text.replace(",", " ").split()
    bad = [t for t in tokens if not re.fullmatch(r"\d+", t)]
    if bad:
        raise InputError(path, f"not a vertex id: {bad[0]!r} (expected non-negative integers)")
    return np.array([int(t) for t in tokens], dtype=np.int64)
