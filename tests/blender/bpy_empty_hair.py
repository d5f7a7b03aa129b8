"""Test helper: Blender's Alembic export of a scene with a hair object not yet groomed.

  bpy_empty_hair.py OUT.abc
      Two hair (Curves) objects: "Good" with two curves of five points, "Empty" with none.
      Blender's exporter writes the empty object's properties with no sample.
"""
import sys

import bpy


def hair(name, sizes):
    data = bpy.data.hair_curves.new(name + "Data")
    if sizes:
        data.add_curves(sizes)
    positions = data.attributes["position"].data
    k = 0
    for i, count in enumerate(sizes):
        for j in range(count):
            positions[k].vector = (0.01 * i, 0.003 * j, 0.1 - 0.2 * j / (count - 1))
            k += 1
    obj = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(obj)


def main():
    args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    hair("Good", [5, 5])
    hair("Empty", [])
    bpy.ops.wm.alembic_export(filepath=args[0], start=1, end=1)


main()
