"""Imports coif's Alembic files with Blender's own importer (bpy) and compares strand and vertex
counts, positions (every frame of the animation) and radii with what coif wrote.

Usage: .deps/bpy-venv/bin/python scripts/check_blender.py DIR
DIR holds static.abc, animated.abc and expected.json from `examples/alembic_check_files.rs`, and
blender_groom.abc / blender_groom_usd.abc: `coif convert` of Blender's own test groom
(tests/data/blender_groom.abc and .usda), compared per curves object with Blender's import of
its own file (curve and point counts, bounding box, radii).
Blender turns Alembic's Y up into its Z up: (x, y, z) -> (x, -z, y).
"""
import json
import os
import sys

import bpy
from mathutils import Vector

TOLERANCE = 1e-5


def import_curves(path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.alembic_import(filepath=path, as_background_job=False)
    objects = [o for o in bpy.context.scene.objects if o.type in ("CURVES", "CURVE")]
    if len(objects) != 1:
        sys.exit(f"{path}: expected one curves object, Blender made {[(o.name, o.type) for o in bpy.context.scene.objects]}")
    return objects[0]


def world_points(obj):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = obj.evaluated_get(depsgraph)
    matrix = evaluated.matrix_world
    positions = evaluated.data.attributes["position"].data
    return [matrix @ Vector(p.vector) for p in positions], evaluated


def compare(label, got, expected_points):
    if len(got) != len(expected_points):
        sys.exit(f"{label}: Blender has {len(got)} points, coif wrote {len(expected_points)}")
    worst = 0.0
    for g, (x, y, z) in zip(got, expected_points):
        worst = max(worst, (g - Vector((x, -z, y))).length)
    if worst > TOLERANCE:
        sys.exit(f"{label}: positions differ by up to {worst:.3g} m")
    return worst


def main():
    folder = sys.argv[1]
    with open(os.path.join(folder, "expected.json")) as f:
        expected = json.load(f)

    obj = import_curves(os.path.join(folder, "static.abc"))
    curves = obj.data
    counts = [c.points_length for c in curves.curves]
    if len(curves.curves) != expected["strands"] or counts != expected["vertex_counts"]:
        sys.exit(f"static: Blender has {len(curves.curves)} curves / {len(curves.points)} points")
    points, evaluated = world_points(obj)
    worst = compare("static", points, expected["static_points"])
    radii = [r.value for r in curves.attributes["radius"].data]
    worst_radius = max(abs(r - w / 2) for r, w in zip(radii, expected["widths"]))
    if worst_radius > 1e-9:
        sys.exit(f"static: radii differ from width/2 by up to {worst_radius:.3g}")
    print(f"static.abc: {obj.type} object, {len(curves.curves)} curves, {len(curves.points)} points; "
          f"positions within {worst:.2g} m, radius = width/2 within {worst_radius:.2g}")

    obj = import_curves(os.path.join(folder, "animated.abc"))
    scene = bpy.context.scene
    frames = expected["frames"]
    print(f"animated.abc: scene frames {scene.frame_start}-{scene.frame_end}, "
          f"modifiers {[m.type for m in obj.modifiers]}")
    worst = 0.0
    for f, expected_points in enumerate(frames):
        scene.frame_set(f + 1)
        points, evaluated = world_points(obj)
        if len(evaluated.data.curves) != expected["strands"]:
            sys.exit(f"frame {f + 1}: {len(evaluated.data.curves)} curves")
        worst = max(worst, compare(f"animated frame {f + 1}", points, expected_points))
    print(f"animated.abc: {len(frames)} frames, {expected['strands']} curves, {expected['vertices']} points "
          f"each; positions within {worst:.2g} m on every frame")
    original = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "blender_groom.abc")
    for name in ("blender_groom.abc", "blender_groom_usd.abc"):
        converted = os.path.join(folder, name)
        if os.path.exists(converted):
            compare_groom(original, converted)
    print("check-blender: OK")


def groom_objects(path):
    """Per curves object (by name): curve count, point count, world bbox, radii."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.alembic_import(filepath=path, as_background_job=False)
    out = {}
    for obj in bpy.context.scene.objects:
        if obj.type not in ("CURVES", "CURVE"):
            continue
        points, evaluated = world_points(obj)
        lo = Vector([min(p[i] for p in points) for i in range(3)])
        hi = Vector([max(p[i] for p in points) for i in range(3)])
        radii = [r.value for r in evaluated.data.attributes["radius"].data]
        out[obj.name.split(".")[0]] = (len(evaluated.data.curves), len(points), lo, hi, radii)
    return out


def compare_groom(original, converted):
    """coif's conversion of Blender's groom, imported by Blender, against Blender's own file."""
    want, got = groom_objects(original), groom_objects(converted)
    for name, (curves, points, lo, hi, radii) in want.items():
        match = [k for k in got if name in k]
        if len(match) != 1:
            sys.exit(f"{converted}: no single curves object for {name}: {list(got)}")
        g_curves, g_points, g_lo, g_hi, g_radii = got[match[0]]
        if (g_curves, g_points) != (curves, points):
            sys.exit(f"{converted} {name}: {g_curves} curves / {g_points} points, Blender's file {curves} / {points}")
        box = max((g_lo - lo).length, (g_hi - hi).length)
        radius = max(abs(a - b) for a, b in zip(g_radii, radii))
        if box > TOLERANCE or radius > 1e-9:
            sys.exit(f"{converted} {name}: bounding box off by {box:.3g} m, radii by {radius:.3g}")
        print(f"{os.path.basename(converted)} {name}: {curves} curves, {points} points; "
              f"bbox within {box:.2g} m, radii within {radius:.2g}")


if __name__ == "__main__":
    main()
