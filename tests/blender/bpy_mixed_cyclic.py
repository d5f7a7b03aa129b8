"""Test helper: Blender's Alembic export of a curve object mixing cyclic and non-cyclic splines.

  bpy_mixed_cyclic.py OUT.abc
      A curve object "Hair" of three poly splines, the middle one cyclic. Blender warns
      ("Cannot export mixed cyclic and non-cyclic curves in the same Curves object") and writes
      the object's properties with no sample.
"""
import sys

import bpy


def main():
    args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    curve = bpy.data.curves.new("Hair", "CURVE")
    curve.dimensions = "3D"
    for k in range(3):
        spline = curve.splines.new("POLY")
        spline.points.add(3)
        for i, point in enumerate(spline.points):
            point.co = (0.02 * k, 0.05 * i, 0.01 * i * i, 1.0)
        spline.use_cyclic_u = k == 1
    hair = bpy.data.objects.new("Hair", curve)
    bpy.context.scene.collection.objects.link(hair)
    bpy.ops.wm.alembic_export(filepath=args[0], start=1, end=1)


main()
