"""Test helper: what Blender's own importer (bpy) makes of a groom coif wrote, as JSON.

  bpy_reimport.py FILE      FILE is .abc (wm.alembic_import) or .usd/.usda/.usdc (wm.usd_import)

For every curves object: its name, curve and point counts, and each attribute whose name starts
with "groom_" (domain, data type, values flattened) -- the guide flag and Unreal's interpolation
attributes a DCC needs to re-interpolate children from guides.
"""
import json
import sys

import bpy


def flatten(attribute):
    out = []
    for item in attribute.data:
        value = item.vector if hasattr(item, "vector") else item.value
        try:
            out.extend(float(x) for x in value)
        except TypeError:
            out.append(float(value))
    return out


def main():
    path = sys.argv[-1]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if path.endswith(".abc"):
        bpy.ops.wm.alembic_import(filepath=path, as_background_job=False)
    else:
        bpy.ops.wm.usd_import(filepath=path)
    objects = []
    for obj in sorted(bpy.context.scene.objects, key=lambda o: o.name):
        if obj.type != "CURVES":
            continue
        curves = obj.data
        objects.append(
            {
                "name": obj.name,
                "curves": len(curves.curves),
                "points": len(curves.points),
                "attributes": {
                    a.name: {"domain": a.domain, "type": a.data_type, "values": flatten(a)}
                    for a in curves.attributes
                    if a.name.startswith("groom_")
                },
            }
        )
    print("BPY-JSON " + json.dumps({"objects": objects}))


main()
