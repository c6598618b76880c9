"""Run by the bpy environment's Python (benchmarks/blender_figure.py): two meshes side by side, rendered with Cycles
on the CPU, intersecting faces red.

    python blender_render.py SHAPES.npz OUT.png   (SHAPES: faces, left, right, left_hit, right_hit)
"""

import sys

import bpy
import numpy as np
from mathutils import Vector


def shaded(name, V, F, hit):
    """An object of the mesh ``V``, ``F`` whose faces ``hit`` (m,) bool are red, the others grey."""
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(V.tolist(), [], F.tolist())
    colours = mesh.color_attributes.new("hit", "FLOAT_COLOR", "FACE")
    colours.data.foreach_set("color", np.where(hit[:, None], [0.85, 0.08, 0.05, 1.0],
                                               [0.75, 0.75, 0.78, 1.0]).astype(np.float32).ravel())
    mesh.polygons.foreach_set("use_smooth", np.ones(len(F), dtype=bool))
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    attribute = material.node_tree.nodes.new("ShaderNodeAttribute")
    attribute.attribute_name = "hit"
    material.node_tree.links.new(attribute.outputs["Color"],
                                 material.node_tree.nodes["Principled BSDF"].inputs["Base Color"])
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)


def stage(extent, out):
    """Camera, sun, a light grey world and Cycles on the CPU; the still rendered to ``out``."""
    scene = bpy.context.scene
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    scene.camera, camera.data.lens = camera, 45
    camera.location, camera.rotation_euler = Vector((0, -3.8 * max(extent), 0.4 * extent[2])), (np.radians(85), 0, 0)
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy, sun.rotation_euler = 3.0, (np.radians(50), np.radians(20), np.radians(30))
    scene.collection.objects.link(sun)
    scene.world = bpy.data.worlds.new("world")
    scene.world.use_nodes = True
    scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.6
    scene.render.engine, scene.cycles.device, scene.cycles.samples = "CYCLES", "CPU", 24
    scene.render.resolution_x, scene.render.resolution_y, scene.render.filepath = 900, 420, out
    bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    shapes, out = sys.argv[-2:]
    d = np.load(shapes)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    centre = 0.5 * (d["left"].min(axis=0) + d["left"].max(axis=0))
    extent = d["left"].max(axis=0) - d["left"].min(axis=0)
    shift = np.array([0.66 * extent[0], 0.0, 0.0])
    shaded("left", d["left"] - centre - shift, d["faces"], d["left_hit"])
    shaded("right", d["right"] - centre + shift, d["faces"], d["right_hit"])
    stage(extent, out)
