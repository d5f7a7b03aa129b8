"""Test helper: a legacy hair particle system (the hair most older Blender grooms are), with
interpolated children, on a head under a scaled and turned rig, exported by Blender twice.

  bpy_particle_hair.py OUT.abc OUT.usda
      A UV sphere "Head" (radius 10 cm) parented to an empty "Rig" scaled ×2, turned and moved,
      with a hair particle system of 12 parents of 5 cm and 3 interpolated children each,
      exported with Blender's Alembic exporter (export_hair) and its USD exporter (which writes
      the particle hair as a curves prim under the head).
"""
import sys

import bpy


def main():
    args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.1, segments=12, ring_count=8)
    head = bpy.context.active_object
    head.name = "Head"
    rig = bpy.data.objects.new("Rig", None)
    bpy.context.scene.collection.objects.link(rig)
    head.parent = rig
    rig.scale = (2.0, 2.0, 2.0)
    rig.location = (0.1, 0.2, 1.5)
    rig.rotation_euler = (0.3, 0.0, 0.5)
    head.modifiers.new("hair", "PARTICLE_SYSTEM")
    settings = head.particle_systems[0].settings
    settings.type = "HAIR"
    settings.count = 12
    settings.hair_length = 0.05
    settings.hair_step = 5
    settings.display_step = 3
    settings.render_step = 3
    settings.child_type = "INTERPOLATED"
    settings.child_percent = 3
    settings.rendered_child_count = 3
    bpy.context.view_layer.update()
    bpy.ops.wm.alembic_export(filepath=args[0], start=1, end=1, export_hair=True)
    bpy.ops.wm.usd_export(filepath=args[1], export_hair=True)


main()
