"""Blender's side of posefix's Alembic caches: run by a Python that has bpy, or by ``blender --background --python``
(:func:`posefix.io.formats.alembic.blender_command`); posefix never imports it.

    read PATH OUT.npz [MESH]    the frames of PATH's mesh MESH (default: its only mesh) into OUT.npz
    write PATH OUT.abc JOB.npz  PATH with the frames of its mesh JOB["mesh"] set to JOB["points"]
    new OUT.abc JOB.npz         a cache of one mesh (JOB: mesh, counts, indices, frames, points), for tests

A problem is one line on stderr, ``posefix-alembic: error: ...``, and exit status 2.
"""

import sys

import bpy
import numpy as np

ERROR = "posefix-alembic: error: "


def fail(message):
    print(ERROR + message, file=sys.stderr, flush=True)
    sys.exit(2)


def load(path):
    """An empty scene with the cache ``path`` imported (its frame range the scene's)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    try:
        result = bpy.ops.wm.alembic_import(filepath=path, set_frame_range=True)
    except RuntimeError as exc:
        fail(f"cannot be read as Alembic ({str(exc).strip().splitlines()[0][:200]})")
    if result != {"FINISHED"} or not bpy.data.objects:
        fail("cannot be read as Alembic (Blender's importer found no archive or nothing in it)")


def chosen(mesh):
    """The mesh object named ``mesh``, or the only one."""
    meshes = sorted(o.name for o in bpy.data.objects if o.type == "MESH")
    listed = ", ".join(meshes[:10]) + (" ..." if len(meshes) > 10 else "")
    if mesh:
        if mesh not in meshes:
            fail(f"no mesh {mesh} (meshes: {listed or 'none'})")
        return bpy.data.objects[mesh]
    if not meshes:
        fail("no mesh in the cache")
    if len(meshes) > 1:
        fail(f"{len(meshes)} meshes ({listed}): choose one with the config's mesh: <name>")
    return bpy.data.objects[meshes[0]]


def sample(obj):
    """The object's evaluated mesh now: (points (n, 3) float32, counts (m,), indices (k,))."""
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    try:
        points = np.empty(3 * len(mesh.vertices), dtype=np.float32)
        mesh.vertices.foreach_get("co", points)
        counts = np.empty(len(mesh.polygons), dtype=np.int32)
        mesh.polygons.foreach_get("loop_total", counts)
        indices = np.empty(len(mesh.loops), dtype=np.int32)
        mesh.loops.foreach_get("vertex_index", indices)
    finally:
        evaluated.to_mesh_clear()
    return points.reshape(-1, 3), counts, indices


def read(path, out, mesh=""):
    load(path)
    obj, scene = chosen(mesh), bpy.context.scene
    frames = list(range(scene.frame_start, scene.frame_end + 1))
    scene.frame_set(frames[0])
    first, counts, indices = sample(obj)
    points = [first]
    for frame in frames[1:]:
        scene.frame_set(frame)
        P, c, i = sample(obj)
        if len(P) != len(first) or not (np.array_equal(c, counts) and np.array_equal(i, indices)):
            fail(f"mesh {obj.name}: frame {frame} has {len(P)} vertices and {len(c)} faces, frame {frames[0]} "
                 f"{len(first)} and {len(counts)}: its topology changes between frames")
        points.append(P)
    np.savez(out, mesh=obj.name, frames=np.array(frames), points=np.stack(points), counts=counts, indices=indices)


def set_frames(obj, frames, points):
    """Make ``obj``'s mesh take ``points`` (k, n, 3) at ``frames`` (k,): one shape key a frame, on at its frame
    alone (constant keys), over a basis at the origin, so that the mix at a frame is its key's points to the bit
    (basis + 1 (key - basis) is not, in float32)."""
    obj.shape_key_clear()
    obj.shape_key_add(name="Basis").data.foreach_set("co", np.zeros(3 * len(obj.data.vertices), dtype=np.float32))
    for frame, P in zip(frames, points):
        key = obj.shape_key_add(name=f"frame {frame}", from_mix=False)
        key.data.foreach_set("co", np.asarray(P, dtype=np.float32).ravel())
        for at, value in ((frames[0], 0.0), (frame, 1.0), (frame + 1, 0.0)):
            key.value = value
            key.keyframe_insert("value", frame=at)
    for curve in obj.data.shape_keys.animation_data.action.fcurves:
        for point in curve.keyframe_points:
            point.interpolation = "CONSTANT"


def export(out, frames):
    bpy.context.scene.frame_start, bpy.context.scene.frame_end = int(frames[0]), int(frames[-1])
    result = bpy.ops.wm.alembic_export(filepath=out, start=int(frames[0]), end=int(frames[-1]), selected=False,
                                       uvs=True, normals=False, face_sets=False, triangulate=False,
                                       apply_subdiv=False, export_custom_properties=False)
    if result != {"FINISHED"}:
        fail(f"{out}: Blender's Alembic exporter failed")


def write(path, out, job):
    load(path)
    data = np.load(job)
    obj = chosen(str(data["mesh"]))
    for modifier in [m for m in obj.modifiers if m.type == "MESH_SEQUENCE_CACHE"]:
        obj.modifiers.remove(modifier)
    set_frames(obj, [int(f) for f in data["frames"]], data["points"])
    export(out, data["frames"])


def new(out, job):
    data = np.load(job)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    counts, indices = data["counts"], data["indices"]
    faces = np.split(indices, np.cumsum(counts)[:-1])
    mesh = bpy.data.meshes.new(str(data["mesh"]))
    mesh.from_pydata(data["points"][0].tolist(), [], [f.tolist() for f in faces])
    obj = bpy.data.objects.new(str(data["mesh"]), mesh)
    bpy.context.scene.collection.objects.link(obj)
    set_frames(obj, [int(f) for f in data["frames"]], data["points"])
    export(out, data["frames"])


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    {"read": read, "write": write, "new": new}[args[0]](*args[1:])
