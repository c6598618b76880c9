"""Mesh file formats, one module each, in a registry by extension (trimesh ``exchange`` style).

Every format module has

* ``LOAD_KWARGS``: extra keyword arguments of ``trimesh.load`` that keep the file's vertex order;
* ``declared_counts(data) -> (nv, nf)``: the counts the file announces itself (None where unknown);
* ``check(path, data)``: raises :class:`posefix.io.errors.InputError` for what trimesh
  would silently change;
* ``encode(V, F, **options) -> bytes``: the mesh in this format, with coordinates that read back
  exactly;
* ``encode_like(source, V, F) -> bytes``: the same, keeping as much of ``source`` (the bytes of an
  input file of this format with the same faces) as the format allows.
"""

from posefix.io.formats import obj, off, ply

FORMATS = {"obj": obj, "ply": ply, "off": off}
"""Format modules by lower-case extension."""
