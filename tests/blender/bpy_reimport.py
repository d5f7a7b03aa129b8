"""Test helper: what Blender's own importer (bpy) makes of a groom coif wrote, as JSON.

  bpy_reimport.py FILE [--frames FIRST:LAST]
      FILE is .abc (wm.alembic_import) or .usd/.usda/.usdc (wm.usd_import)

For every curves object: its name, curve and point counts, and each attribute whose name starts
with "groom_" (domain, data type, values flattened) -- the guide flag and Unreal's interpolation
attributes a DCC needs to re-interpolate children from guides. With --frames, also the world
positions of every curves object's points at each scene frame FIRST..LAST (evaluated: object
animation, cache modifiers), in Blender's space (Z up, metres).
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


def world_points(obj):
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    matrix = evaluated.matrix_world
    out = []
    for p in evaluated.data.attributes["position"].data:
        out.extend(matrix @ p.vector)
    return out


def main():
    args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
    path = args[0]
    frames = None
    if "--frames" in args:
        first, last = args[args.index("--frames") + 1].split(":")
        frames = range(int(first), int(last) + 1)
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
    result = {"objects": objects}
    if frames is not None:
        curves_objects = sorted((o for o in bpy.context.scene.objects if o.type == "CURVES"), key=lambda o: o.name)
        result["frames"] = []
        for frame in frames:
            bpy.context.scene.frame_set(frame)
            result["frames"].append({o.name: world_points(o) for o in curves_objects})
    print("BPY-JSON " + json.dumps(result))


main()
