"""Run by the bpy environment's Python (tests/io/formats/test_alembic.py): Alembic caches that are not pose
libraries, written by Blender's exporter.

    python alembic_cases.py CASE OUT.abc  (CASE: empty, changing or two)
"""

import sys

import bpy


def empty(out):
    """A cache with a locator and no mesh."""
    bpy.context.scene.collection.objects.link(bpy.data.objects.new("Locator", None))
    bpy.ops.wm.alembic_export(filepath=out, start=1, end=2)


def changing(out):
    """A sphere whose Decimate modifier's ratio is animated: its vertices and faces change between frames."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=16, ring_count=8)
    modifier = bpy.context.active_object.modifiers.new("Decimate", "DECIMATE")
    for frame, ratio in ((1, 1.0), (3, 0.3)):
        modifier.ratio = ratio
        modifier.keyframe_insert("ratio", frame=frame)
    bpy.ops.wm.alembic_export(filepath=out, start=1, end=3)


def two(out):
    """Two meshes, Cube and Sphere."""
    bpy.ops.mesh.primitive_cube_add()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=8, ring_count=4)
    bpy.ops.wm.alembic_export(filepath=out, start=1, end=2)


if __name__ == "__main__":
    bpy.ops.wm.read_factory_settings(use_empty=True)
    {"empty": empty, "changing": changing, "two": two}[sys.argv[1]](sys.argv[2])
