"""Run by the bpy environment's Python (tests/blender/test_shape_keys.py): the add-on's zip installed as Blender's
preferences install it (into $HOME's Blender folder), a mesh with shape keys from an .npz file, one action, its
outcome written to OUT.json (and OUT.npz: every shape key's positions).

    python scene.py ACTION IN.npz OUT ZIP PYTHON  (ACTION: new, in_place or bad; PYTHON: the posefix environment's)
"""

import hashlib
import json
import sys
from pathlib import Path

import bpy
import numpy as np

import addon_utils  # (importable once bpy is)

MODULE = "bl_ext.user_default.posefix"
"""The add-on's module once installed into Blender's user repository."""


def install_addon(archive, python):
    """Install the add-on's zip and enable it, with ``python`` as its posefix Python."""
    bpy.ops.extensions.package_install_files(filepath=archive, repo="user_default", enable_on_install=True)
    bpy.context.preferences.addons[MODULE].preferences.python = python


def limb(data, name="limb", keys=True):
    """An object of the mesh in ``data`` with its poses as shape keys (the basis: the reference), made active."""
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(data["reference"].tolist(), [], data["faces"].tolist())
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    if keys:
        obj.shape_key_add(name="Basis")
        for k, pose_name in enumerate(data["names"]):
            key = obj.shape_key_add(name=str(pose_name), from_mix=False)
            key.data.foreach_set("co", data["poses"][k].astype(np.float32).ravel())
            key.value = 0.1 * (k + 1)
    bpy.context.view_layer.objects.active = obj
    return obj


def digest(obj):
    """A hash of the object's data: its vertices, faces, shape keys (names, positions, settings) and properties."""
    h = hashlib.sha256(obj.name.encode())
    if obj.type == "MESH":
        co = np.empty(3 * len(obj.data.vertices), dtype=np.float32)
        obj.data.vertices.foreach_get("co", co)
        h.update(co.tobytes())
        for key in (obj.data.shape_keys.key_blocks if obj.data.shape_keys else []):
            data = np.empty(3 * len(key.data), dtype=np.float32)
            key.data.foreach_get("co", data)
            h.update(f"{key.name}{key.value}{key.mute}{key.relative_key.name}".encode() + data.tobytes())
    h.update(json.dumps({k: str(v) for k, v in obj.items()}, sort_keys=True).encode())
    return h.hexdigest()


def repaired(data, in_place, out):
    """Repair every key as new keys, or in place the keys 2 and 4 (key 2 muted, key 3 relative to key 1)."""
    obj = limb(data)
    obj.data.shape_keys.key_blocks[2].mute = True
    obj.data.shape_keys.key_blocks[3].relative_key = obj.data.shape_keys.key_blocks[1]
    names = ",".join(str(n) for n in data["names"][1::2]) if in_place else ""
    result = bpy.ops.posefix.repair_shape_keys("EXEC_DEFAULT", in_place=in_place, keys=names)
    keys = obj.data.shape_keys.key_blocks
    arrays = {}
    for key in keys:
        co = np.empty(3 * len(key.data), dtype=np.float32)
        key.data.foreach_get("co", co)
        arrays[key.name] = co.reshape(-1, 3)
    np.savez(f"{out}.npz", **arrays)
    info = {"result": sorted(result), "keys": {k.name: {"relative_key": k.relative_key.name, "value": round(k.value, 6),
                                                         "mute": k.mute} for k in keys},
            "results": json.loads(obj["posefix_shape_keys"])}
    Path(f"{out}.json").write_text(json.dumps(info))


def bad(data, out):
    """The bad inputs: each one's error line and whether the object's data changed."""
    cases = {}
    cases["no shape keys"] = limb(data, "bare", keys=False)
    cases["a non-mesh object"] = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    bpy.context.scene.collection.objects.link(cases["a non-mesh object"])
    cases["a key with another vertex count"] = limb(data, "grown")
    cases["a key with another vertex count"].data.vertices.add(1)
    cases["modifiers that change the topology"] = limb(data, "subdivided")
    cases["modifiers that change the topology"].modifiers.new("Subdivision", "SUBSURF")
    cases["no posefix environment"] = limb(data, "unset")
    outcome = {}
    for case, obj in cases.items():
        if case == "no posefix environment":
            bpy.context.preferences.addons[MODULE].preferences.python = "/nonexistent/python"
        bpy.context.view_layer.objects.active = obj
        before = digest(obj)
        try:
            bpy.ops.posefix.repair_shape_keys("EXEC_DEFAULT")
            line = None
        except RuntimeError as exc:
            line = str(exc).strip()
        outcome[case] = {"line": line, "changed": digest(obj) != before}
    Path(f"{out}.json").write_text(json.dumps(outcome))


if __name__ == "__main__":
    action, source, out, archive, python = sys.argv[1:6]
    install_addon(archive, python)
    try:
        with np.load(source) as npz:
            data = {k: npz[k] for k in npz.files}
        if action == "bad":
            bad(data, out)
        else:
            repaired(data, action == "in_place", out)
    finally:
        addon_utils.disable(MODULE)  # (a bpy process with the add-on's classes registered does not exit)
