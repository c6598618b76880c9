"""Pose libraries written into USD, glTF and Alembic files by the formats' own libraries (usd-core, pygltflib;
Blender's Alembic exporter), for the tests of the container readers and writers and of the workflow on them."""

import numpy as np
import pygltflib
from pxr import Sdf, Usd, UsdGeom, UsdSkel, Vt


def _usd_mesh(path, F, prim="/Character/Body"):
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.Xform.Define(stage, prim.rsplit("/", 1)[0])
    geom = UsdGeom.Mesh.Define(stage, prim)
    geom.GetFaceVertexCountsAttr().Set(Vt.IntArray([len(f) for f in F]))
    geom.GetFaceVertexIndicesAttr().Set(Vt.IntArray([int(i) for f in F for i in f]))
    return stage, geom


def write_usd_frames(path, V_ref, poses, F, rest=True, prim="/Character/Body", first=1):
    """A USD file whose mesh ``prim`` has ``V_ref`` (n, 3) as its default points (``rest``) and the poses
    [(n, 3)] as time samples at frames ``first``, ``first`` + 1, ...; faces ``F`` (m, 3) or polygons (lists)."""
    stage, geom = _usd_mesh(path, F, prim)
    points = geom.GetPointsAttr()
    if rest:
        points.Set(Vt.Vec3fArray.FromNumpy(np.asarray(V_ref, dtype=np.float32)))
    for k, V in enumerate(poses):
        points.Set(Vt.Vec3fArray.FromNumpy(np.asarray(V, dtype=np.float32)), Usd.TimeCode(first + k))
    stage.SetStartTimeCode(first)
    stage.SetEndTimeCode(first + len(poses) - 1)
    stage.GetRootLayer().Save()
    return path


def write_usd_blend_shapes(path, V_ref, poses, F, names, sparse=(), prim="/Character/Body"):
    """A USD file whose mesh ``prim`` has points ``V_ref`` and one UsdSkel blend shape per pose, called
    ``names``; the shapes whose index is in ``sparse`` hold offsets of their moved points only (pointIndices)."""
    stage, geom = _usd_mesh(path, F, prim)
    base = np.asarray(V_ref, dtype=np.float32)
    geom.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(base))
    binding = UsdSkel.BindingAPI.Apply(geom.GetPrim())
    targets = []
    for k, (name, V) in enumerate(zip(names, poses)):
        shape = UsdSkel.BlendShape.Define(stage, f"{prim}/shape{k}")
        delta = np.asarray(V, dtype=np.float32) - base
        if k in sparse:
            moved = np.flatnonzero(np.any(delta != 0, axis=1))
            shape.GetPointIndicesAttr().Set(Vt.IntArray.FromNumpy(moved.astype(np.int32)))
            delta = delta[moved]
        shape.GetOffsetsAttr().Set(Vt.Vec3fArray.FromNumpy(delta))
        targets.append(Sdf.Path(f"{prim}/shape{k}"))
    binding.GetBlendShapesAttr().Set(list(names))
    binding.GetBlendShapeTargetsRel().SetTargets(targets)
    stage.GetRootLayer().Save()
    return path


def write_gltf(path, V_ref, poses, F, names=None, sparse=(), mesh="Body"):
    """A glTF file (``.glb`` or ``.gltf`` with an embedded buffer) with one mesh ``mesh``: base positions
    ``V_ref`` (float32), indices ``F``, one morph target per pose (displacements from the base, float32) named
    ``names`` in ``extras.targetNames``; the targets whose index is in ``sparse`` as sparse accessors (only the
    moved points), with no buffer view of their own."""
    blob, views, accessors = bytearray(), [], []

    def add(array, target=None):
        data = np.ascontiguousarray(array).tobytes()
        blob.extend(b"\0" * (-len(blob) % 4))
        views.append(pygltflib.BufferView(buffer=0, byteOffset=len(blob), byteLength=len(data), target=target))
        blob.extend(data)
        return len(views) - 1

    base = np.asarray(V_ref, dtype=np.float32)
    accessors.append(pygltflib.Accessor(bufferView=add(base, 34962), componentType=5126, count=len(base),
                                        type="VEC3", min=base.min(0).tolist(), max=base.max(0).tolist()))
    accessors.append(pygltflib.Accessor(bufferView=add(np.asarray(F, dtype=np.uint32).ravel(), 34963),
                                        componentType=5125, count=3 * len(F), type="SCALAR"))
    targets = []
    for k, V in enumerate(poses):
        delta = np.asarray(V, dtype=np.float32) - base
        finite = np.where(np.isfinite(delta), delta, 0)  # min and max in JSON, also of a bad target
        accessor = pygltflib.Accessor(componentType=5126, count=len(base), type="VEC3",
                                      min=finite.min(0).tolist(), max=finite.max(0).tolist())
        if k in sparse:
            moved = np.flatnonzero(np.any(delta != 0, axis=1)).astype(np.uint32)
            accessor.sparse = pygltflib.Sparse(
                count=len(moved), indices=pygltflib.AccessorSparseIndices(bufferView=add(moved), componentType=5125),
                values=pygltflib.AccessorSparseValues(bufferView=add(delta[moved])))
        else:
            accessor.bufferView = add(delta)
        accessors.append(accessor)
        targets.append({"POSITION": len(accessors) - 1})
    primitive = pygltflib.Primitive(attributes=pygltflib.Attributes(POSITION=0), indices=1, targets=targets)
    extras = {"targetNames": list(names)} if names else {}
    gltf = pygltflib.GLTF2(scene=0, scenes=[pygltflib.Scene(nodes=[0])], nodes=[pygltflib.Node(mesh=0)],
                           meshes=[pygltflib.Mesh(name=mesh, primitives=[primitive], extras=extras,
                                                  weights=[0.0] * len(poses))],
                           accessors=accessors, bufferViews=views, buffers=[pygltflib.Buffer(byteLength=len(blob))])
    gltf.set_binary_blob(bytes(blob))
    if str(path).endswith(".gltf"):
        gltf.convert_buffers(pygltflib.BufferFormat.DATAURI)
    gltf.save(str(path))
    return path


def library_into_containers(folder, out, stem, alembic=False):
    """The pose library in ``folder`` (a reference ``*-reference.*`` and its poses) written as ``<stem>.usdc`` (the
    poses as frames 1, 2, ... after the reference's default points), ``<stem>.glb`` (morph targets named by the pose
    files) and, with ``alembic``, ``<stem>.abc`` (the reference as frame 1, the poses after it) in ``out``
    (benchmarks/containers.py); returns the paths by kind and the pose names in file order."""
    from posefix.io.library import discover_library
    from posefix.io.meshes import read_mesh
    library = discover_library(folder)
    V_ref, F = read_mesh(library.reference.path)
    poses = [read_mesh(p.path)[0] for p in library.poses]
    names = [p.name for p in library.poses]
    paths = {"usdc": write_usd_frames(out / f"{stem}.usdc", V_ref, poses, F),
             "glb": write_gltf(out / f"{stem}.glb", V_ref, poses, F, names)}
    if alembic:
        paths["abc"] = write_alembic_frames(out / f"{stem}.abc", V_ref, poses, F)
    return paths, names


def write_alembic_frames(path, V_ref, poses, F, mesh="Body"):
    """An Alembic cache of one mesh ``mesh`` whose frames 1, 2, ... are ``V_ref`` then ``poses`` (float32), written
    by Blender's exporter ($POSEFIX_BLENDER: a Python with bpy; posefix.io.formats.alembic's script)."""
    import tempfile

    from posefix.io.formats.alembic import run_blender
    points = np.stack([V_ref, *poses]).astype(np.float32)
    with tempfile.TemporaryDirectory() as scratch:
        job = f"{scratch}/job.npz"
        np.savez(job, mesh=mesh, counts=np.full(len(F), 3), indices=np.asarray(F).ravel(),
                 frames=np.arange(1, len(points) + 1), points=points)
        run_blender(path, "new", path, job)
    return path
