"""USD pose libraries (Pixar's usd-core): a ``UsdGeom.Mesh`` whose ``points`` are time-sampled, one pose a frame,
or a mesh with ``UsdSkel`` blend shapes, one pose a shape (the mesh's points plus the shape's offsets).

Frames are named ``<file stem>-<frame>`` (``character-012``: integer frames zero-padded to one width, so names sort
in time order), the default value of time-sampled points, where authored, ``<file stem>-reference``; blend shapes
by their names in ``skel:blendShapes``. A file written back (:meth:`UsdContainer.write`) is the composed stage
flattened into one layer of the input's format, with only the points (and a time-sampled ``extent``) of the
repaired frames, or the offsets of the repaired shapes, replaced.
"""

import os
import re
import tempfile

import numpy as np
from pxr import Tf, Usd, UsdGeom, UsdSkel, UsdUtils, Vt

from posefix.io.containers import REST, Container, container_stem, fan_triangles, frame_labels, pose_names
from posefix.io.errors import InputError
from posefix.io.files import atomic_path


class UsdContainer(Container):
    """A USD mesh and its frames or blend shapes (:class:`posefix.io.containers.Container`); ``details``: the
    ``stage`` and, for blend shapes, the ``base`` points (n, 3) float64."""

    def where(self, name):
        key = self.members[name]
        if isinstance(key, str):
            return f"mesh {self.mesh}, blend shape {key}"
        return f"mesh {self.mesh}, " + ("default (rest) points" if key is None else f"frame {key:g}")

    def values(self, name):
        key = self.members[name]
        if not isinstance(key, str):
            value = _points_attr(self.details["stage"], self.mesh).Get(_time(key))
            return np.asarray(value if value is not None else [], dtype=np.float64).reshape(-1, 3)
        P = self.details["base"].copy()
        offsets, indices = _shape_offsets(self.details["stage"], key)
        if indices is None and len(offsets) != self.n or indices is not None and len(indices) != len(offsets):
            raise InputError(self.path, f"{self.where(name)}: {len(offsets)} offsets for "
                                        f"{self.n if indices is None else len(indices)} points")
        P[slice(None) if indices is None else indices] += offsets
        return P

    def write(self, out, positions):
        stage = _open_stage(self.path)
        stage.SetEditTarget(stage.GetSessionLayer())  # the file's layers stay as read (Usd shares them)
        geom = UsdGeom.Mesh(stage.GetPrimAtPath(self.mesh))
        points = geom.GetPointsAttr()
        kept = {key: points.Get(_time(key)) for name, key in self.members.items()
                if self.rebase and name not in positions}
        for key, value in kept.items():  # a layer's time samples replace a weaker layer's: every frame is authored
            points.Set(value, _time(key))
        for name, X in positions.items():
            key = self.members[name]
            if isinstance(key, str):
                _set_offsets(stage, key, np.asarray(X, dtype=np.float64) - self.details["base"])
            else:
                _set_points(geom, np.asarray(X, dtype=np.float64), key)
        _export(stage, str(out))


def open_container(path, mesh=None):
    """The :class:`UsdContainer` of the mesh prim ``mesh`` (a path; None: the only mesh) of the USD file ``path``:
    its frames when its points are time-sampled, else its blend shapes."""
    stage = _open_stage(path)
    prim = _mesh_prim(path, stage, mesh)
    geom = UsdGeom.Mesh(prim)
    where = f"mesh {prim.GetPath()}"
    for attr in (geom.GetFaceVertexCountsAttr(), geom.GetFaceVertexIndicesAttr()):
        if attr.GetNumTimeSamples() > 1:
            raise InputError(path, f"{where}: {attr.GetName()} is time-sampled: the faces change between frames")
    times = geom.GetPointsAttr().GetTimeSamples()
    rest = geom.GetPointsAttr().Get(Usd.TimeCode.Default())
    if times:
        members = dict(zip(pose_names(path, frame_labels(container_stem(path), times)), times))
        if rest is not None:
            members = {f"{container_stem(path)}-{REST}": None, **members}
        details = {}
    else:
        members, details = _blend_shapes(path, prim, rest)
    n = len(_points_attr(stage, str(prim.GetPath())).Get(_time(next(iter(members.values())))) or [])
    faces = fan_triangles(f"{path} ({where})", geom.GetFaceVertexCountsAttr().Get() or [],
                          geom.GetFaceVertexIndicesAttr().Get() or [], n)
    if not len(faces):
        raise InputError(path, f"{where} has no faces")
    rest_name = f"{container_stem(path)}-{REST}" if rest is not None else None
    return UsdContainer(path=path, mesh=str(prim.GetPath()), members=members, rest=rest_name, faces=faces, n=n,
                        rebase=bool(times), details={"stage": stage, **details})


def _open_stage(path):
    """The USD stage of ``path``; InputError with USD's own reason when it cannot be read."""
    try:
        return Usd.Stage.Open(str(path), Usd.Stage.LoadAll)
    except Tf.ErrorException as exc:
        raise InputError(path, f"cannot be read as USD: {_usd_reason(exc)}") from None


def _usd_reason(exc):
    """The message of a USD error without its C++ location, one line."""
    text = " ".join(str(exc).split())
    messages = re.findall(r" : '(.*?)'(?= Error in |\s*$)", text)
    return ("; ".join(dict.fromkeys(messages)) or text)[:300]


def _mesh_prim(path, stage, mesh):
    """The mesh prim ``mesh`` (path) of ``stage``, or its only mesh; InputError listing the meshes otherwise."""
    meshes = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    listed = ", ".join(str(p.GetPath()) for p in meshes[:10]) + (" ..." if len(meshes) > 10 else "")
    if mesh is not None:
        chosen = [p for p in meshes if str(p.GetPath()) == mesh]
        if not chosen:
            raise InputError(path, f"no mesh prim {mesh} (meshes: {listed or 'none'})")
        return chosen[0]
    if not meshes:
        raise InputError(path, "no mesh (UsdGeom.Mesh prim) in the file")
    if len(meshes) > 1:
        raise InputError(path, f"{len(meshes)} meshes ({listed}): choose one with the config's mesh: <prim path>")
    return meshes[0]


def _blend_shapes(path, prim, rest):
    """``(members, details)`` of a mesh's UsdSkel blend shapes: {name: BlendShape prim path} in the order of
    ``skel:blendShapes``, the rest pose (the mesh's points) first."""
    binding = UsdSkel.BindingAPI(prim)
    labels = list(binding.GetBlendShapesAttr().Get() or [])
    targets = [str(t) for t in binding.GetBlendShapeTargetsRel().GetTargets()]
    where = f"mesh {prim.GetPath()}"
    if not labels and not targets:
        raise InputError(path, f"{where}: its points have no time samples and it has no blend shapes: no poses")
    if len(labels) != len(targets):
        raise InputError(path, f"{where}: {len(labels)} blend shape names but {len(targets)} blend shape targets")
    if rest is None:
        raise InputError(path, f"{where} has blend shapes but no points to apply them to")
    for target in targets:
        if not prim.GetStage().GetPrimAtPath(target).IsA(UsdSkel.BlendShape):
            raise InputError(path, f"{where}: blend shape target {target} is not a BlendShape prim")
    rest_name = f"{container_stem(path)}-{REST}"
    members = {rest_name: None, **dict(zip(pose_names(path, labels, rest_name), targets))}
    return members, {"base": np.asarray(rest, dtype=np.float64).reshape(-1, 3)}


def _time(key):
    return Usd.TimeCode.Default() if key is None or isinstance(key, str) else Usd.TimeCode(key)


def _points_attr(stage, mesh):
    return UsdGeom.Mesh(stage.GetPrimAtPath(mesh)).GetPointsAttr()


def _shape_offsets(stage, target):
    """``(offsets (k, 3) float64, point indices (k,) int64 or None)`` of the BlendShape prim ``target``."""
    shape = UsdSkel.BlendShape(stage.GetPrimAtPath(target))
    offsets = np.asarray(shape.GetOffsetsAttr().Get() or [], dtype=np.float64).reshape(-1, 3)
    indices = shape.GetPointIndicesAttr().Get()
    return offsets, (None if indices is None else np.asarray(indices, dtype=np.int64))


def _set_offsets(stage, target, delta):
    """Author the offsets ``delta`` (n, 3) of every point on BlendShape ``target``: its own points keep their
    order, the points the repair moved besides them are appended (a shape without ``pointIndices`` stays dense)."""
    shape = UsdSkel.BlendShape(stage.GetPrimAtPath(target))
    _, indices = _shape_offsets(stage, target)
    if indices is not None:
        moved = np.flatnonzero(np.any(delta != 0, axis=1))
        indices = np.concatenate([indices, np.setdiff1d(moved, indices)])
        shape.GetPointIndicesAttr().Set(Vt.IntArray.FromNumpy(indices.astype(np.int32)))
        delta = delta[indices]
    shape.GetOffsetsAttr().Set(Vt.Vec3fArray.FromNumpy(delta.astype(np.float32)))


def _set_points(geom, X, key):
    """Author the points ``X`` (n, 3) of ``geom`` at frame ``key`` (None: the default value), and its extent
    there when the extent is time-sampled."""
    attr = geom.GetPointsAttr()
    array = Vt.Vec3dArray if "3d" in str(attr.GetTypeName()) else Vt.Vec3fArray
    values = array.FromNumpy(X.astype(np.float64 if array is Vt.Vec3dArray else np.float32))
    attr.Set(values, _time(key))
    if key is not None and geom.GetExtentAttr().GetNumTimeSamples():
        geom.GetExtentAttr().Set(UsdGeom.PointBased.ComputeExtent(values), _time(key))


def _export(stage, out):
    """The composed ``stage`` flattened into one layer at ``out``, atomically; ``.usdz``: packaged from a
    ``.usdc`` layer."""
    suffix = os.path.splitext(out)[1].lower()
    with atomic_path(out) as tmp, tempfile.TemporaryDirectory(dir=os.path.dirname(tmp) or ".") as scratch:
        layer = os.path.join(scratch, "layer" + (".usdc" if suffix == ".usdz" else suffix))
        if not stage.Export(layer, addSourceFileComment=False):
            raise InputError(out, "USD could not write the file")
        if suffix == ".usdz":
            package = os.path.join(scratch, "package.usdz")
            if not UsdUtils.CreateNewUsdzPackage(layer, package):
                raise InputError(out, "USD could not write the .usdz package")
            layer = package
        os.replace(layer, tmp)
