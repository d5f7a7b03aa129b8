"""Test helper: one hair curves object under scaled transforms, exported by Blender twice.

  bpy_scaled_hair.py OUT.abc OUT.usda
      A hair curves object "Hair" of two 4-point curves, every point of radius 30 µm, scaled ×2
      under an empty "Rig" scaled ×1.5 (world scale 3, so a world radius of 90 µm), exported with
      Blender's Alembic exporter and its USD exporter.
"""
import sys

import bpy
from mathutils import Vector


def main():
    args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    curves = bpy.data.hair_curves.new("HairData")
    curves.add_curves([4, 4])
    for i in range(8):
        curves.points[i].position = Vector((0.01 * (i // 4), 0.003 * (i % 4), 0.02 * (i % 4)))
    radius = curves.attributes.get("radius") or curves.attributes.new("radius", "FLOAT", "POINT")
    for i in range(8):
        radius.data[i].value = 30e-6
    hair = bpy.data.objects.new("Hair", curves)
    rig = bpy.data.objects.new("Rig", None)
    for obj in (rig, hair):
        bpy.context.scene.collection.objects.link(obj)
    hair.parent = rig
    hair.location = (0.0, 0.0, 0.1)
    hair.scale = (2.0, 2.0, 2.0)
    rig.location = (0.05, 0.0, 1.5)
    rig.scale = (1.5, 1.5, 1.5)
    bpy.context.view_layer.update()
    bpy.ops.wm.alembic_export(filepath=args[0], start=1, end=1)
    bpy.ops.wm.usd_export(filepath=args[1])


main()
