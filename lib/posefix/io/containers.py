"""Pose libraries in one file: USD (time-sampled points, UsdSkel blend shapes), glTF morph targets and Alembic
caches (frames).

A container holds one mesh whose poses are its frames, blend shapes or morph targets. Its format module
(:mod:`posefix.io.formats.usd`, :mod:`posefix.io.formats.gltf`, :mod:`posefix.io.formats.alembic`, imported on first
use: usd-core is slow to import)
opens it as a :class:`Container`: the pose names (members) in file order, the rest pose, the triangles, and per
member its points and a phrase saying where it is in the file. ``Container.write`` writes the same file with some
members' positions replaced. Every problem is an :class:`~posefix.io.errors.InputError` naming the file, and the
prim or target, in one line.
"""

import hashlib
from abc import ABC, abstractmethod
import importlib
import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from posefix.io.errors import InputError
from posefix.io.files import atomic_write_bytes

CONTAINER_SUFFIXES = {".usd": "usd", ".usda": "usd", ".usdc": "usd", ".usdz": "usd", ".gltf": "gltf", ".glb": "gltf",
                      ".abc": "alembic"}
"""Format module (under :mod:`posefix.io.formats`) by lower-case file extension."""
REST = "reference"
"""Pose name suffix of a container's rest pose: ``<file stem>-reference`` (the base points of blend shapes or
morph targets, the default value of time-sampled points), named as a folder's reference file would be."""


@dataclass
class Container(ABC):
    """One mesh of a container file and its poses.

    Attributes
    ----------
    path : str
    mesh : str
        The mesh's path in the file (USD prim path, glTF mesh name).
    members : dict
        Pose name -> the format's key (time code, blend shape, target index), in file order.
    rest : str or None
        The member that is the rest pose (base points), if the file has one.
    faces : (m, 3) int64
        The mesh's polygons as triangles (:func:`fan_triangles`); the file's own faces are written back untouched.
    n : int
        Number of points of every pose.
    rebase : bool
        Whether any member can be the reference (frames); False where poses are offsets from the rest pose.
    """

    path: str
    mesh: str
    members: dict
    rest: object
    faces: np.ndarray
    n: int
    rebase: bool = True
    details: dict = field(default_factory=dict)
    """Format-specific data of the opened file (the format module's own)."""

    @abstractmethod
    def where(self, name):
        """Where the member ``name`` is in the file, e.g. ``mesh /Root/Body, frame 12`` (str)."""

    @abstractmethod
    def values(self, name):
        """The points of member ``name`` as the file holds them, unchecked: (k, 3) float64."""

    def points(self, name):
        """The points of member ``name``: (n, 3) float64, checked by :func:`check_points`."""
        P = self.values(name)
        check_points(self.path, self.where(name), P, self.n)
        return P

    def digest(self, name):
        """sha256 (hex) of member ``name``'s points and the mesh's faces (of its problem where it has one): a pose
        whose digest is unchanged is the same pose, however else the file changed."""
        try:
            data = self.values(name).tobytes()
        except InputError as exc:
            data = str(exc).encode()
        return hashlib.sha256(data + self.faces.tobytes()).hexdigest()

    @abstractmethod
    def write(self, out, positions):
        """Write the file to ``out`` (same format) with the members of ``positions`` ({name: (n, 3) float})
        replaced, atomically; everything else as read."""


def container_format(path):
    """Name of the format module of the container file ``path`` (``usd``, ``gltf``, ``alembic``), or None."""
    return CONTAINER_SUFFIXES.get(os.path.splitext(str(path))[1].lower())


def container_stem(path):
    """The library name of a container file: its name without the extension (``character`` for
    ``character.usdz``).

    Examples
    --------
    >>> container_stem("shots/character.anim.glb")
    'character.anim'
    """
    return os.path.splitext(os.path.basename(str(path)))[0]


def open_container(path, mesh=None):
    """Open the container file ``path`` (:data:`CONTAINER_SUFFIXES`) at its mesh ``mesh`` (None: the only mesh
    with poses) as a :class:`Container`; InputError for an unknown extension or what the format refuses."""
    fmt = container_format(path)
    if fmt is None:
        raise InputError(path, f"not a pose container (expected {', '.join(CONTAINER_SUFFIXES)})")
    if not os.path.isfile(path):
        raise InputError(path, "no such file")
    return importlib.import_module(f"posefix.io.formats.{fmt}").open_container(str(path), mesh)


def fan_triangles(path, counts, indices, n):
    """Triangles of polygons given as corner counts and concatenated corner indices, each polygon a fan from
    its first corner (as trimesh triangulates an OBJ's quads).

    Parameters
    ----------
    path : str
        The file, for errors.
    counts : (k,) int
        Corners of each polygon (at least 3).
    indices : (sum(counts),) int
        Point indices of the corners, polygon after polygon, each in 0..n-1.
    n : int
        Number of points.

    Returns
    -------
    (m, 3) int64
        ``sum(counts - 2)`` triangles, polygon after polygon.

    Examples
    --------
    >>> fan_triangles("x", [4], [0, 1, 2, 3], 4).tolist()
    [[0, 1, 2], [0, 2, 3]]
    """
    counts, indices = np.asarray(counts, dtype=np.int64), np.asarray(indices, dtype=np.int64)
    if (counts < 3).any():
        f = int(np.argmax(counts < 3))
        raise InputError(path, f"face {f} has {counts[f]} corners: not a polygon, cannot be triangulated")
    if counts.sum() != len(indices):
        raise InputError(path, f"the faces have {counts.sum()} corners but {len(indices)} corner indices")
    if len(indices) and (indices.min() < 0 or indices.max() >= n):
        bad = int(np.argmax((indices < 0) | (indices >= n)))
        raise InputError(path, f"corner {bad} has point index {indices[bad]}, out of range 0..{n - 1}")
    first = np.repeat(np.cumsum(counts) - counts, counts - 2)
    step = np.arange(len(first)) - np.repeat(np.cumsum(counts - 2) - (counts - 2), counts - 2)
    return np.stack([indices[first], indices[first + step + 1], indices[first + step + 2]], axis=1)


def check_points(path, where, P, n):
    """Raise :class:`InputError` naming ``path`` and ``where`` unless ``P`` (k, 3) has ``n`` finite points."""
    if len(P) != n:
        raise InputError(path, f"{where}: {len(P)} points, the mesh has {n}")
    bad = ~np.isfinite(P).all(axis=1)
    if bad.any():
        raise InputError(path, f"{where}: {bad.sum()} points are NaN or infinite (first: point {np.argmax(bad)})")


def frame_labels(stem, times):
    """``<stem>-<frame>`` for each time code (float); integer frames zero-padded to the widest.

    Examples
    --------
    >>> frame_labels("anim", [1.0, 2.0, 12.0])
    ['anim-01', 'anim-02', 'anim-12']
    """
    if all(float(t).is_integer() for t in times):
        width = max(len(str(abs(int(t)))) for t in times)
        return [f"{stem}-{'-' if t < 0 else ''}{abs(int(t)):0{width}d}" for t in times]
    return [f"{stem}-{t:g}" for t in times]


def pose_names(path, labels, rest=None):
    """Pose names of members labelled ``labels`` (frame numbers, blend shape or target names), in order.

    Characters a file name or a Snakemake rule cannot carry (``/``, braces, spaces, control characters) become
    ``_``; InputError when two members get the same name, or one the name of the rest pose ``rest``.

    Examples
    --------
    >>> pose_names("x.glb", ["jaw open", "smile"])
    ['jaw_open', 'smile']
    """
    names = [re.sub(r"[^\w.+-]", "_", str(label)).lstrip(".") or "_" for label in labels]
    seen = {rest: "the rest pose"} if rest else {}
    for label, name in zip(labels, names):
        if name in seen:
            raise InputError(path, f"two poses would both be named '{name}' ({seen[name]} and {label!r}): "
                                   "rename one")
        seen[name] = repr(label)
    return names


def member_digests(path, mesh=None, cache=None):
    """{pose name: :meth:`Container.digest`} of every member of the container file ``path``.

    Parameters
    ----------
    path : str or Path
    mesh : str, optional
        As for :func:`open_container`.
    cache : str or Path, optional
        JSON file of the digests by file, mesh, size and modification time: an unchanged file is not read again.

    Returns
    -------
    dict
    """
    st = os.stat(path)
    key, entries = f"{os.path.abspath(path)}|{mesh}", {}
    if cache is not None and os.path.isfile(cache):
        try:
            entries = json.loads(Path(cache).read_text())
        except ValueError:  # a cache cut short: start over
            entries = {}
    entry = entries.get(key)
    if entry is None or entry["stat"] != [st.st_size, st.st_mtime_ns]:
        box = open_container(path, mesh)
        entry = entries[key] = {"stat": [st.st_size, st.st_mtime_ns],
                                "digests": {name: box.digest(name) for name in box.members}}
        if cache is not None:
            atomic_write_bytes(cache, json.dumps(entries, indent=0, sort_keys=True).encode())
    return entry["digests"]
