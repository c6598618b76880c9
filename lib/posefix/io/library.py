"""Pose libraries on disk: discovery of the reference and the poses, and their validation.

A pose library is a folder of triangle meshes (:mod:`posefix.io.meshes`) that share one
face array. Every problem is raised as :class:`~posefix.io.errors.InputError` naming the
file (or folder) and the problem in one line.
"""

import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posefix.mesh.geometry import bbox_diagonal, edge_lengths, face_areas
from posefix.mesh.topology import edges
from posefix.mesh.weld import Weld
from posefix.io.containers import container_stem, open_container
from posefix.io.errors import InputError
from posefix.io.meshes import MESH_SUFFIXES, MeshFile, mesh_file, read_mesh

DEGENERATE_AREA_REL = 1e-14
"""Reference faces with area below this times the squared bbox diagonal count as zero-area."""
SEAM_APART_REL = 1e-3
"""Vertices split along a seam in the reference must stay within this times its mean edge length in a pose."""


FAR_REL = 100.0
"""A pose vertex farther than this many of the reference's bbox diagonals from the reference's bbox centre is an
error of the file (a pose moves its parts within a few diagonals; the fit would fail much later on it)."""

MIN_REFERENCE_VERTICES = 15
"""Fewest vertices of a usable reference: the terms of the space-time method's quadratic space-time polynomial
(``posefix.spacetime.rbf.POLY_TERMS``; the I/O layer imports no method, a test checks that they agree)."""


@dataclass(frozen=True)
class Library:
    """A pose library: one reference and the target poses to repair, in name order."""

    folder: str
    name: str
    reference: MeshFile
    poses: tuple
    refused: tuple = ()
    """``(path, cause)`` of the mesh files left out of the library, one pair each (:func:`file_problem`)."""
    container: str = None
    """The USD or glTF file the library is in (:func:`container_library`; its meshes are unpacked into ``folder``
    by stage unpack), or None for a folder of mesh files."""
    mesh: str = None
    """The container's mesh (USD prim path, glTF mesh name) that holds the poses."""

    def pose(self, name):
        """The :class:`~posefix.io.meshes.MeshFile` of the pose called ``name``."""
        for p in self.poses:
            if p.name == name:
                return p
        raise KeyError(name)


def file_problem(path):
    """Why the mesh file at ``path`` cannot be a pose of a library, one line (str), or None.

    A link to nowhere or a loop of links, something that is not a regular file, an unreadable file, and a file name
    that Snakemake's rules cannot carry (braces read as wildcards, control characters).

    Examples
    --------
    >>> file_problem("walk{2}.obj")
    "braces in the file name (Snakemake's rules read them as wildcards): rename the file"
    """
    name = os.path.basename(path)
    if "{" in name or "}" in name:
        return "braces in the file name (Snakemake's rules read them as wildcards): rename the file"
    if not name.isprintable():
        return "a control character in the file name: rename the file"
    try:
        mode = os.stat(path).st_mode
    except OSError as exc:
        return f"a link to {os.readlink(path)}: {exc.strerror}" if os.path.islink(path) else exc.strerror
    if not stat.S_ISREG(mode):
        return "not a regular file"
    return None if os.access(path, os.R_OK) else "not readable (permissions)"


def discover_library(folder, reference=None, poses=None, name=None):
    """Find the reference and target poses in a folder (hidden files, e.g. macOS ``._*``, and sub-folders,
    e.g. ``__MACOSX/``, are not read).

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

    Returns
    -------
    Library
        Mesh files that cannot be poses (:func:`file_problem`) are left out, in ``refused``.

    Raises
    ------
    InputError
        Missing folder, no meshes, no or several reference candidates, unknown names, a reference that cannot be
        read (:func:`file_problem`), two files with the same pose name, or no target pose.
    """
    folder = Path(folder)
    files, by_name = _mesh_files(folder)
    ref = _pick_reference(folder, files, by_name, reference)
    if poses:
        missing = [p for p in poses if _lookup(by_name, p) is None]
        if missing:
            raise InputError(folder, f"pose(s) not found: {', '.join(missing)}")
        chosen = [_lookup(by_name, p) for p in poses]
    else:
        chosen = files
    chosen, refused = _usable_poses(folder, ref, chosen)
    return Library(folder=str(folder), name=name or folder.resolve().name, reference=ref, poses=chosen,
                   refused=refused)


def container_library(path, folder, reference=None, poses=None, name=None, mesh=None):
    """A pose library in one USD or glTF file (:mod:`posefix.io.containers`), its meshes to be unpacked into
    ``folder`` as ``<pose>.ply``.

    Parameters
    ----------
    path : str or Path
        The container file.
    folder : str or Path
        Where stage unpack writes each pose as a mesh file (the library's ``folder``).
    reference : str, optional
        The pose (frame) that is the reference, by name or by frame number (``12``); default: the rest pose (the
        base of blend shapes and morph targets, the default value of time-sampled points), else the first frame.
        Only frames can be another.
    poses : list of str, optional
        Names of the poses to repair; default: every other member (but the rest pose when a frame is the reference).
    name : str, optional
        Library name; default: the file's name without extension.
    mesh : str, optional
        The mesh holding the poses when the file has several (USD prim path, glTF mesh name).

    Returns
    -------
    Library
    """
    problem = file_problem(path)
    if problem:
        raise InputError(path, problem)
    box = open_container(path, mesh)
    ref = _container_reference(box, reference)
    members = [m for m in box.members if m != ref and not (box.rest == m and ref != box.rest)]
    if poses:
        missing = [p for p in poses if p not in members]
        if missing:
            raise InputError(path, f"pose(s) not in {box.mesh}: {', '.join(missing)} (poses: "
                                   f"{', '.join(members[:8])}{' ...' if len(members) > 8 else ''})")
        members = [m for m in members if m in poses]
    if not members:
        raise InputError(path, f"{box.mesh}: no poses besides the reference")
    unpacked = [MeshFile(path=f"{folder}/{m}.ply", name=m, fmt="ply", gz=False) for m in [ref, *members]]
    return Library(folder=str(folder), name=name or container_stem(path), reference=unpacked[0],
                   poses=tuple(unpacked[1:]), container=str(path), mesh=box.mesh)


def _container_reference(box, reference):
    """The member of ``box`` that is the reference: ``reference`` (a name, or a frame's number), or the rest
    pose, or the first member."""
    if reference is None:
        return box.rest or next(iter(box.members))
    found = [m for m, key in box.members.items()
             if reference == m or (isinstance(key, float) and str(reference) in (f"{key:g}", str(key)))]
    if not found:
        raise InputError(box.path, f"reference '{reference}' is not a pose of {box.mesh}")
    if found[0] != box.rest and not box.rebase:
        raise InputError(box.path, f"reference '{reference}': the reference of blend shapes and morph targets is "
                                   f"the base they are offsets from ({box.rest})")
    return found[0]


def find_reference(folder, reference=None):
    """The :class:`~posefix.io.meshes.MeshFile` of the reference in ``folder``, picked as :func:`discover_library`
    picks it, whether or not the poses are there yet (a USD or glTF library's poses are unpacked one by one)."""
    files, by_name = _mesh_files(Path(folder))
    return _pick_reference(Path(folder), files, by_name, reference)


def _mesh_files(folder):
    """``(files, by_name)``: the mesh files of ``folder`` in name order (not hidden ones) and by pose name;
    InputError for a missing folder, no mesh file, or two files of one pose name."""
    if not folder.is_dir():
        raise InputError(folder, "not a folder")
    files = [mesh_file(p) for p in sorted(folder.iterdir())
             if (p.is_file() or p.is_symlink()) and not p.name.startswith(".")]  # hidden: ._x.obj (macOS), ...
    files = [f for f in files if f is not None]
    if not files:
        raise InputError(folder, f"no mesh files {MESH_SUFFIXES}")
    by_name = {}
    for f in files:
        if f.name in by_name:
            raise InputError(f.path, f"same pose name '{f.name}' as {os.path.basename(by_name[f.name].path)}")
        by_name[f.name] = f
    return files, by_name


def _usable_poses(folder, ref, chosen):
    """``(poses, refused)``: the files of ``chosen`` but the reference that can be poses, in name order, and
    ``(path, cause)`` of those that cannot (:func:`file_problem`); InputError if the reference cannot or no pose
    is left."""
    problem = file_problem(ref.path)
    if problem:
        raise InputError(ref.path, problem)
    causes = {f.path: file_problem(f.path) for f in chosen}
    refused = tuple((path, cause) for path, cause in causes.items() if cause)
    poses = tuple(sorted({f.name: f for f in chosen if f.name != ref.name and not causes[f.path]}.values(),
                         key=lambda f: f.name))
    if not poses:
        raise InputError(folder, "no target poses besides the reference" + "".join(
            f"; {os.path.basename(path)}: {cause}" for path, cause in refused))
    return poses, refused


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


def check_reference(path, V, F):
    """Raise :class:`InputError` when the reference is too small for the space-time fit (fewer than
    :data:`MIN_REFERENCE_VERTICES` vertices), has vertices in no face (the solvers' Laplacians would be singular
    there: "Factor is exactly singular") or degenerate or zero-area faces."""
    if len(V) < MIN_REFERENCE_VERTICES:
        raise InputError(path, f"reference has {len(V)} vertices: the repair needs at least "
                               f"{MIN_REFERENCE_VERTICES} (the terms of the fit's quadratic space-time polynomial)")
    repeated = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
    if repeated.any():
        f = int(np.argmax(repeated))
        raise InputError(path, f"reference has {repeated.sum()} degenerate faces repeating a vertex (first: face {f} {F[f].tolist()})")
    unused = np.setdiff1d(np.arange(len(V)), F)
    if len(unused):
        listed = ", ".join(map(str, unused[:10])) + (f" and {len(unused) - 10} more" if len(unused) > 10 else "")
        raise InputError(path, f"reference has {len(unused)} vertices in no face ({listed}): a loose vertex has no "
                               "surface to move with (remove it from the library's meshes)")
    d = bbox_diagonal(V)
    tiny = face_areas(V, F) <= DEGENERATE_AREA_REL * d * d
    if tiny.any():
        f = int(np.argmax(tiny))
        raise InputError(path, f"reference has {tiny.sum()} zero-area faces (first: face {f})")


def check_pose(path, V, F, V_ref, F_ref):
    """Raise :class:`InputError` unless a pose matches the reference's vertex count and faces and lies within
    :data:`FAR_REL` bounding-box diagonals of it."""
    if len(V) != len(V_ref):
        raise InputError(path, f"{len(V)} vertices, the reference has {len(V_ref)}")
    if F.shape != F_ref.shape:
        raise InputError(path, f"{len(F)} faces, the reference has {len(F_ref)}")
    differ = np.any(F != F_ref, axis=1)
    if differ.any():
        f = int(np.argmax(differ))
        raise InputError(path, f"face array differs from the reference ({differ.sum()} faces; first: face {f} "
                               f"{F[f].tolist()} vs {F_ref[f].tolist()})")
    centre, d = 0.5 * (V_ref.min(axis=0) + V_ref.max(axis=0)), bbox_diagonal(V_ref)
    far = np.linalg.norm(V - centre, axis=1) / d
    if far.max(initial=0.0) > FAR_REL:
        v = int(np.argmax(far))
        raise InputError(path, f"vertex {v} {V[v].tolist()} is {far[v]:.3g} bounding-box diagonals of the reference "
                               f"from its centre (at most {FAR_REL:g}): a typo or a unit mismatch?")


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


def check_seams(path, weld, X, V_ref, F):
    """Raise :class:`InputError` when vertices that coincide in the reference (``weld``) are apart in the
    pose ``X`` (n, 3): the pose splits the mesh where the reference does not."""
    tol = SEAM_APART_REL * float(edge_lengths(V_ref, edges(F)).mean())
    apart = weld.apart(X, tol)
    if len(apart):
        a, b = apart[0]
        raise InputError(path, f"vertices {a} and {b} coincide in the reference (a seam) but are "
                               f"{np.linalg.norm(X[a] - X[b]):.3g} apart here ({len(apart)} such vertices)")


def read_welded_reference(path):
    """The reference with its split vertices welded (:class:`~posefix.mesh.weld.Weld`): (V (k, 3), F (m, 3),
    weld); a mesh without seams comes back unchanged (``k == n``)."""
    V, F = read_reference(path)
    weld = Weld.of(V, F)
    return weld.weld(V), weld.faces(F), weld


def read_welded_pair(reference_path, target_path):
    """Reference and target with the reference's split vertices welded: (V_ref (k, 3), V_tgt (k, 3),
    F (m, 3), weld); :class:`InputError` naming the target when a seam of the reference opens in it."""
    V_ref, V_tgt, F = read_pose_pair(reference_path, target_path)
    weld = Weld.of(V_ref, F)
    check_seams(target_path, weld, V_tgt, V_ref, F)
    return weld.weld(V_ref), weld.weld(V_tgt), weld.faces(F), weld


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
