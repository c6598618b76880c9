"""glTF 2.0 pose libraries (``.gltf``, ``.glb``; pygltflib): a mesh with morph targets, its base positions the
reference and every morph target a pose (base plus the target's ``POSITION`` displacements).

The primitives of the mesh are one mesh of the library, their points one after the other. Targets are named by the
mesh's ``extras.targetNames`` where present, else ``target-<k>``; the base ``<file stem>-reference``. Accessors are
read as the specification says: interleaved (``byteStride``), normalized integers, sparse. A file written back
(:meth:`GltfContainer.write`) keeps every object and index; only the repaired targets' ``POSITION`` accessors get
new float32 displacements (in place where they were dense float32, else in a new buffer view) and their min/max.
"""

import base64

import numpy as np
import pygltflib

from posefix.io.containers import REST, Container, container_stem, pose_names
from posefix.io.errors import InputError, one_line
from posefix.io.files import atomic_write_bytes

COMPONENTS = {5120: "i1", 5121: "u1", 5122: "i2", 5123: "u2", 5125: "u4", 5126: "f4"}
"""numpy dtype (little-endian) of each glTF ``componentType``."""
WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
TRIANGLES = 4
READ_EXTENSIONS = {"KHR_mesh_quantization"}
"""Required extensions the reader handles (quantized positions are normalized or plain integer accessors)."""


class GltfContainer(Container):
    """A glTF mesh and its morph targets (:class:`posefix.io.containers.Container`); ``details``: the ``gltf``
    (pygltflib.GLTF2), its ``buffers`` (list of bytes), the ``base`` points (n, 3) float64 and the ``spans``
    [(primitive, first point, point count)]."""

    def where(self, name):
        key = self.members[name]
        return f"mesh {self.mesh}, " + ("base positions" if key is None else f"morph target {key} ({name})")

    def values(self, name):
        key, (gltf, buffers) = self.members[name], (self.details["gltf"], self.details["buffers"])
        P = self.details["base"].copy()
        for primitive, first, count in self.details["spans"] if key is not None else ():
            accessor = _target_position(primitive.targets[key])
            if accessor is not None:
                P[first:first + count] += read_accessor(self.path, gltf, buffers, accessor, count)
        return P

    def write(self, out, positions):
        gltf, buffers = _load(self.path)
        buffers = [bytearray(b) for b in buffers]
        primitives = _mesh_by_name(self.path, gltf, self.mesh)[1].primitives
        for name, X in positions.items():
            key = self.members[name]
            if key is None:
                raise InputError(out, f"{self.where(name)}: the base positions are the reference, not rewritten")
            for primitive, (_, first, count) in zip(primitives, self.details["spans"]):
                delta = (np.asarray(X[first:first + count], dtype=np.float64)
                         - self.details["base"][first:first + count]).astype(np.float32)
                _put_accessor(gltf, buffers, _position_accessor(gltf, primitive.targets[key], count), delta)
        atomic_write_bytes(out, _encode(gltf, buffers, str(out).lower().endswith(".glb")))


def open_container(path, mesh=None):
    """The :class:`GltfContainer` of the mesh ``mesh`` (its name or index; None: the only mesh with morph targets)
    of the glTF file ``path``."""
    gltf, buffers = _load(path)
    index, chosen = _mesh_by_name(path, gltf, mesh)
    label = chosen.name or str(index)
    where = f"mesh {label}"
    counts = {len(p.targets or []) for p in chosen.primitives}
    if counts != {max(counts, default=0)} or not max(counts, default=0):
        raise InputError(path, f"{where}: its primitives have {sorted(counts)} morph targets: no poses")
    spans, base, faces, first = [], [], [], 0
    for k, primitive in enumerate(chosen.primitives):
        if (primitive.mode if primitive.mode is not None else TRIANGLES) != TRIANGLES:
            raise InputError(path, f"{where}, primitive {k}: mode {primitive.mode}, not triangles (4)")
        if primitive.attributes.POSITION is None:
            raise InputError(path, f"{where}, primitive {k}: no POSITION attribute")
        points = read_accessor(path, gltf, buffers, primitive.attributes.POSITION, None)
        faces.append(first + _triangles(path, gltf, buffers, primitive, len(points), f"{where}, primitive {k}"))
        spans.append((primitive, first, len(points)))
        base.append(points)
        first += len(points)
    n_targets = counts.pop()
    labels = (chosen.extras or {}).get("targetNames") or []
    if len(labels) != n_targets:
        labels = [f"target-{k:0{len(str(n_targets - 1))}d}" for k in range(n_targets)]
    rest = f"{container_stem(path)}-{REST}"
    members = {rest: None, **dict(zip(pose_names(path, labels, rest), range(n_targets)))}
    return GltfContainer(path=path, mesh=label, members=members, rest=rest,
                         faces=np.concatenate(faces), n=first, rebase=False,
                         details={"gltf": gltf, "buffers": buffers, "base": np.concatenate(base), "spans": spans})


def _target_position(target):
    """The ``POSITION`` accessor index of a morph target (pygltflib Attributes or dict), or None."""
    return target.get("POSITION") if isinstance(target, dict) else getattr(target, "POSITION", None)


def _load(path):
    """``(gltf, buffers)``: the pygltflib document of ``path`` and the bytes of each of its buffers; InputError
    when the file or a buffer cannot be read."""
    try:
        gltf = pygltflib.GLTF2().load(str(path))
    except Exception as exc:  # noqa: BLE001  (json, struct and IO errors of a bad file)
        raise InputError(path, f"cannot be read as glTF: {one_line(exc)}") from None
    if gltf is None:
        raise InputError(path, "cannot be read as glTF: no JSON chunk")
    unread = sorted(set(gltf.extensionsRequired or ()) - READ_EXTENSIONS)
    if unread:
        raise InputError(path, f"needs the glTF extension(s) {', '.join(unread)}, which posefix does not read "
                               "(export without compression)")
    buffers = []
    for k, buffer in enumerate(gltf.buffers):
        try:
            data = gltf.get_data_from_buffer_uri(buffer.uri)
        except Exception as exc:  # noqa: BLE001  (a missing .bin file, a bad data URI)
            raise InputError(path, f"buffer {k} ({buffer.uri}) cannot be read: {one_line(exc)}") from None
        if data is None or len(data) < (buffer.byteLength or 0):
            raise InputError(path, f"buffer {k} has {0 if data is None else len(data)} bytes, the file declares "
                                   f"{buffer.byteLength} (truncated file?)")
        buffers.append(bytes(data))
    return gltf, buffers


def _mesh_by_name(path, gltf, mesh):
    """``(index, Mesh)`` of the mesh called ``mesh`` (name or index), or of the only mesh with morph targets."""
    named = {m.name or str(k): (k, m) for k, m in enumerate(gltf.meshes)}
    if mesh is not None:
        found = named.get(str(mesh))
        if found is None:
            raise InputError(path, f"no mesh {mesh} (meshes: {', '.join(named) or 'none'})")
        return found
    morphed = [(k, m) for k, m in enumerate(gltf.meshes) if any(p.targets for p in m.primitives)]
    if not gltf.meshes:
        raise InputError(path, "no mesh in the file")
    if not morphed:
        raise InputError(path, f"no mesh with morph targets (meshes: {', '.join(named)}): no poses")
    if len(morphed) > 1:
        names = ", ".join(m.name or str(k) for k, m in morphed)
        raise InputError(path, f"{len(morphed)} meshes with morph targets ({names}): choose one with the config's "
                               "mesh: <name>")
    return morphed[0]


def _triangles(path, gltf, buffers, primitive, n, where):
    """The (m, 3) int64 triangles of a TRIANGLES primitive with ``n`` points (its indices, or 0..n-1)."""
    if primitive.indices is None:
        index = np.arange(n, dtype=np.int64)
    else:
        index = read_accessor(path, gltf, buffers, primitive.indices, None).astype(np.int64).ravel()
    if len(index) % 3 or not len(index):
        raise InputError(path, f"{where}: {len(index)} indices, not a whole number of triangles")
    if index.max() >= n:
        raise InputError(path, f"{where}: index {index.max()} is out of range 0..{n - 1}")
    return index.reshape(-1, 3)


def read_accessor(path, gltf, buffers, index, count):
    """The values of accessor ``index``: (count, k) float64 (integers as stored; normalized ones scaled to
    [-1, 1] or [0, 1]; sparse substitutions applied); InputError when ``count`` (None: any) differs or the data
    runs past its buffer view."""
    a = gltf.accessors[index]
    if count is not None and a.count != count:
        raise InputError(path, f"accessor {index}: {a.count} values, the mesh has {count} points")
    width = WIDTHS[a.type]
    values = (np.zeros((a.count, width)) if a.bufferView is None else
              _view_values(path, gltf, buffers, (a.bufferView, a.byteOffset), (a.componentType, width, a.count)))
    if a.sparse is not None:
        s = a.sparse
        at = _view_values(path, gltf, buffers, (s.indices.bufferView, s.indices.byteOffset),
                          (s.indices.componentType, 1, s.count)).astype(np.int64).ravel()
        if len(at) and at.max() >= a.count:
            raise InputError(path, f"accessor {index}: sparse index {at.max()} out of range 0..{a.count - 1}")
        values[at] = _view_values(path, gltf, buffers, (s.values.bufferView, s.values.byteOffset),
                                  (a.componentType, width, s.count))
    return _normalized(values, a.componentType) if a.normalized else values


def _view_values(path, gltf, buffers, at, layout):
    """``count`` elements of ``width`` components of type ``component`` (``layout``) at ``(bufferView, byte
    offset)`` (``at``), as (count, width) float64."""
    (view_index, offset), (component, width, count) = at, layout
    view = gltf.bufferViews[view_index]
    dtype = np.dtype("<" + COMPONENTS[component])
    stride = view.byteStride or dtype.itemsize * width
    start = (view.byteOffset or 0) + (offset or 0)
    end = start + stride * (count - 1) + dtype.itemsize * width if count else start
    data = buffers[view.buffer]
    if end > (view.byteOffset or 0) + view.byteLength or end > len(data):
        raise InputError(path, f"buffer view {view_index}: {count} values need {end} bytes, it has "
                               f"{min((view.byteOffset or 0) + view.byteLength, len(data))} (truncated file?)")
    return np.ndarray((count, width), dtype, buffer=data, offset=start,
                      strides=(stride, dtype.itemsize)).astype(np.float64)


def _normalized(values, component):
    """Normalized integers as the glTF specification maps them: unsigned c / max, signed max(c / max, -1)."""
    info = np.iinfo(np.dtype(COMPONENTS[component]))
    return np.maximum(values / info.max, -1.0)


def _position_accessor(gltf, target, count):
    """The ``POSITION`` accessor index of the morph target ``target`` (pygltflib Attributes or dict); a new
    float32 accessor of ``count`` points where it has none (the primitive does not move in that target: the
    repair may move it)."""
    index = _target_position(target)
    if index is None:
        gltf.accessors.append(pygltflib.Accessor(componentType=5126, count=count, type="VEC3"))
        index = len(gltf.accessors) - 1
        if isinstance(target, dict):
            target["POSITION"] = index
        else:
            target.POSITION = index
    return index


def _put_accessor(gltf, buffers, index, values):
    """Make accessor ``index`` hold ``values`` (n, 3) float32: written over its data where that is dense,
    tightly packed float32, else appended to buffer 0 as a new buffer view (the accessor no longer sparse)."""
    a = gltf.accessors[index]
    view = gltf.bufferViews[a.bufferView] if a.bufferView is not None else None
    dense = (view is not None and a.sparse is None and a.componentType == 5126 and not a.normalized
             and view.byteStride in (None, 12))
    data = values.astype("<f4").tobytes()
    if dense:
        start = (view.byteOffset or 0) + (a.byteOffset or 0)
        buffers[view.buffer][start:start + len(data)] = data
    else:
        buffers[0].extend(b"\0" * (-len(buffers[0]) % 4))
        gltf.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=len(buffers[0]), byteLength=len(data)))
        buffers[0].extend(data)
        a.bufferView, a.byteOffset, a.componentType, a.normalized, a.sparse = len(gltf.bufferViews) - 1, 0, 5126, \
            False, None
    a.min, a.max = values.min(axis=0).tolist(), values.max(axis=0).tolist()


def _encode(gltf, buffers, binary):
    """The bytes of the document with ``buffers``: GLB (buffer 0 the binary chunk) or glTF JSON with every buffer
    embedded as a data URI."""
    for k, (buffer, data) in enumerate(zip(gltf.buffers, buffers)):
        buffer.byteLength = len(data)
        buffer.uri = None if binary and k == 0 else (
            "data:application/octet-stream;base64," + base64.b64encode(bytes(data)).decode("ascii"))
    if binary:
        gltf.set_binary_blob(bytes(buffers[0]))
        return b"".join(gltf.save_to_bytes())
    gltf.destroy_binary_blob()
    return gltf.gltf_to_json().encode("utf-8")
