"""Test helper: Blender's Alembic export of a Bézier curve object.

  bpy_bezier.py OUT.abc
      A curve object "Guides" (moved off the origin) of three 3D Bézier splines of three knots,
      with free handles and a radius per knot, exported with Blender's Alembic exporter. Blender
      writes each knot and the handles between them into P (7 points a spline) and one width per
      knot (the `varying` count, one per segment end) with no geoScope.
"""
import sys

import bpy


def main():
    args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    curve = bpy.data.curves.new("Guides", "CURVE")
    curve.dimensions = "3D"
    for k in range(3):
        spline = curve.splines.new("BEZIER")
        spline.bezier_points.add(2)
        for i, point in enumerate(spline.bezier_points):
            x, y, z = 0.02 * k, 0.05 * i, 0.01 * i * i + 0.003 * k
            point.co = (x, y, z)
            point.handle_left = (x - 0.004 * i, y - 0.02, z - 0.005 * k)
            point.handle_right = (x + 0.003 * k, y + 0.02, z + 0.01)
            point.radius = 0.001 * (1 + i) + 0.0004 * k
    guides = bpy.data.objects.new("Guides", curve)
    guides.location = (0.1, -0.05, 0.2)
    bpy.context.scene.collection.objects.link(guides)
    bpy.ops.wm.alembic_export(filepath=args[0], start=1, end=1)


main()
