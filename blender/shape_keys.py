"""A mesh's shape keys as posefix's poses, and the repaired poses back as shape keys (no Blender interface here).

The basis (the reference key) is the reference; every other key's positions (``co``, as if its value were 1) are a
pose. The repair needs triangles: the mesh's loop triangles, which keep its vertices and their order.
"""

import numpy as np

RESULTS = "posefix_shape_keys"
"""The object's custom property holding the last repair's results (JSON: a list of the pose job's lines)."""

SUFFIX = ".repaired"
"""A repaired key's name is its key's name and this (``as new keys``)."""


def problem(obj, names=(), depsgraph=None):
    """Why the shape keys of ``obj`` cannot be repaired, one line (str), or None. ``names``: the keys to repair
    (none: all); ``depsgraph``: the evaluated scene, to see whether modifiers change the mesh's topology."""
    if obj is None:
        return "no active object: select a mesh with shape keys"
    if obj.type != "MESH":
        return f"{obj.name} is {'an' if obj.type[0] in 'AEIOU' else 'a'} {obj.type.lower()}, not a mesh"
    keys = obj.data.shape_keys.key_blocks if obj.data.shape_keys else []
    if len(keys) < 2:
        return f"{obj.name}: no shape keys to repair (the basis is the reference, every other key a pose)"
    unknown = [name for name in names if name not in keys]
    if unknown:
        return f"{obj.name}: no shape key named '{unknown[0]}'"
    for key in keys:
        if len(key.data) != len(obj.data.vertices):
            return f"{obj.name}: shape key '{key.name}' has {len(key.data)} vertices, the mesh {len(obj.data.vertices)}"
    return _topology_problem(obj, depsgraph) if depsgraph is not None else None


def _topology_problem(obj, depsgraph):
    """Which of ``obj``'s modifiers changes its vertex or face count (one line), or None."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        same = (len(mesh.vertices), len(mesh.polygons)) == (len(obj.data.vertices), len(obj.data.polygons))
    finally:
        evaluated.to_mesh_clear()
    if same:
        return None
    names = ", ".join(f"'{m.name}' ({m.type.lower()})" for m in obj.modifiers if m.show_viewport) or "its modifiers"
    return (f"{obj.name}: modifiers change the mesh's vertices or faces ({names}): apply or disable them first (the "
            "shape keys are the mesh's own vertices)")


def pose_keys(obj, names=()):
    """The keys to repair: those named (``names``), else every key but the basis and the repaired ones, list."""
    keys = obj.data.shape_keys.key_blocks
    if names:
        return [keys[name] for name in names]
    return [k for k in keys[1:] if not k.name.endswith(SUFFIX) and k != obj.data.shape_keys.reference_key]


def positions(key):
    """A shape key's positions, (n, 3) float64 (Blender stores float32)."""
    co = np.empty(3 * len(key.data), dtype=np.float32)
    key.data.foreach_get("co", co)
    return co.reshape(-1, 3).astype(np.float64)


def triangles(mesh):
    """The mesh's loop triangles as vertex indices, (m, 3) int64."""
    mesh.calc_loop_triangles()
    F = np.empty(3 * len(mesh.loop_triangles), dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", F)
    return F.reshape(-1, 3).astype(np.int64)


def job_arrays(obj, keys):
    """The pose job's arrays (``posefix.workflow.pose_job``) of ``obj`` and its ``keys``, dict."""
    reference = obj.data.shape_keys.reference_key
    return {"reference": positions(reference), "faces": triangles(obj.data),
            "poses": np.stack([positions(k) for k in keys]), "names": np.array([k.name for k in keys])}


def write_key(obj, key, V, in_place):
    """Put the repaired positions ``V`` (n, 3) into ``key`` (``in_place``) or into the key ``<name>.repaired``
    (made if need be) with ``key``'s relative key, value, range, vertex group, interpolation and mute. Returns the
    key written."""
    if not in_place:
        keys = obj.data.shape_keys.key_blocks
        out = keys.get(key.name + SUFFIX) or obj.shape_key_add(name=key.name + SUFFIX, from_mix=False)
        for attribute in ("relative_key", "slider_min", "slider_max", "value", "vertex_group", "interpolation",
                          "mute"):
            setattr(out, attribute, getattr(key, attribute))
        key = out
    key.data.foreach_set("co", np.asarray(V, dtype=np.float32).ravel())
    obj.data.update()
    return key
