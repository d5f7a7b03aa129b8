"""Test helper: what Blender's own importer (bpy) makes of a groom file, as JSON.

  bpy_reimport.py FILE [--frames FIRST:LAST] [--hide-and-export NAME OUT.abc]
      FILE is .abc (wm.alembic_import) or .usd/.usda/.usdc/.usdz (wm.usd_import)
      --hide-and-export: hides the objects whose names start with NAME (or with any of
      several NAMEs joined by commas; the eye in the outliner) and exports the scene to OUT.abc
      with Blender's Alembic exporter.

For every curves object ("objects"): its name, curve and point counts, the set of its curve types
(Blender's `curve_type` codes: 0 Catmull-Rom, the default when the attribute is absent, 1 poly,
2 Bézier, 3 NURBS), whether any curve is cyclic, the radius of every point, the world positions
of its points (evaluated: object transforms, cache modifiers) and each attribute whose name
starts with "groom_" (domain, data type, values flattened) -- the guide flag and Unreal's
interpolation attributes a DCC needs to re-interpolate children from guides -- and, for Bézier
curves, the world positions of each point's left and right handles ("handles"). For every mesh
object ("meshes"): its name, vertex and face counts, world vertex positions, UV map names, the
UVs of each map and the world-space normal of every face corner, and whether it has custom normals. With --frames, also the world positions of every curves and mesh
object at each scene frame FIRST..LAST. All in Blender's space (Z up, metres, or the file's
units for Alembic, which has none).
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


def evaluated(obj):
    return obj.evaluated_get(bpy.context.evaluated_depsgraph_get())


def world_points(obj, attribute="position"):
    data = evaluated(obj)
    matrix = data.matrix_world
    if obj.type == "MESH":
        return [x for v in data.data.vertices for x in matrix @ v.co]
    return [x for p in data.data.attributes[attribute].data for x in matrix @ p.vector]


def curves_object(obj):
    curves = evaluated(obj).data
    attributes = curves.attributes
    types = sorted({a.value for a in attributes["curve_type"].data}) if "curve_type" in attributes else [0]
    cyclic = "cyclic" in attributes and any(a.value for a in attributes["cyclic"].data)
    return {
        "name": obj.name,
        "curves": len(curves.curves),
        "points": len(curves.points),
        "curve_types": types,
        "cyclic": cyclic,
        "radii": [a.value for a in attributes["radius"].data] if "radius" in attributes else [],
        "positions": world_points(obj),
        "handles": {
            side: world_points(obj, f"handle_{side}")
            for side in ("left", "right")
            if f"handle_{side}" in attributes
        },
        "attributes": {
            a.name: {"domain": a.domain, "type": a.data_type, "values": flatten(a)}
            for a in attributes
            if a.name.startswith("groom_")
        },
    }


def mesh_object(obj):
    data = evaluated(obj)
    mesh = data.data
    # Directions turn with the inverse transpose of the object's matrix (an up-axis change on
    # import rotates the object, not its data).
    normal_matrix = data.matrix_world.to_3x3().inverted().transposed()
    return {
        "name": obj.name,
        "vertices": len(mesh.vertices),
        "faces": len(mesh.polygons),
        "positions": world_points(obj),
        "uv_maps": [uv.name for uv in mesh.uv_layers],
        "custom_normals": mesh.has_custom_normals,
        # Per face corner, in Blender's corner order.
        "uvs": {uv.name: [x for c in uv.uv for x in c.vector] for uv in mesh.uv_layers},
        "corner_normals": [x for n in mesh.corner_normals for x in (normal_matrix @ n.vector).normalized()],
    }


def main():
    args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
    path = args[0]
    frames = None
    if "--frames" in args:
        first, last = args[args.index("--frames") + 1].split(":")
        frames = range(int(float(first)), int(float(last)) + 1)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if path.endswith(".abc"):
        bpy.ops.wm.alembic_import(filepath=path, as_background_job=False)
    else:
        bpy.ops.wm.usd_import(filepath=path)
    scene = bpy.context.scene
    if "--hide-and-export" in args:
        at = args.index("--hide-and-export")
        names, out = args[at + 1].split(","), args[at + 2]
        for obj in scene.objects:
            if any(obj.name.startswith(name) for name in names):
                obj.hide_set(True)
        bpy.ops.wm.alembic_export(filepath=out, evaluation_mode="VIEWPORT")
    by_name = sorted(scene.objects, key=lambda o: o.name)
    curves = [o for o in by_name if o.type == "CURVES"]
    meshes = [o for o in by_name if o.type == "MESH"]
    if frames is not None:
        scene.frame_set(frames[0])
    result = {
        "objects": [curves_object(o) for o in curves],
        "meshes": [mesh_object(o) for o in meshes],
        "other_types": sorted({o.type for o in by_name} - {"CURVES", "MESH", "EMPTY"}),
    }
    if frames is not None:
        result["frames"] = []
        for frame in frames:
            scene.frame_set(frame)
            result["frames"].append({o.name: world_points(o) for o in curves + meshes})
    print("BPY-JSON " + json.dumps(result))


main()
