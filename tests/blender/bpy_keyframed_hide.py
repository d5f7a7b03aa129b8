"""Test helper: a hide keyframed in Blender, exported by its Alembic exporter.

  bpy_keyframed_hide.py SOURCE.abc OUT.abc
      Imports SOURCE (tests/data/blender_groom.abc: "Guides" and "Hair" curves objects on a
      "Head" mesh), keys the Guides object's hide_viewport and hide_render visible at frame 1,
      hidden at 2, visible at 3 (the eye and camera in the outliner, keyframed), and exports
      frames 1 to 3 to OUT with Blender's Alembic exporter.
"""
import sys

import bpy


def main():
    args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
    source, out = args[0], args[1]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.alembic_import(filepath=source, as_background_job=False)
    guides = [o for o in bpy.context.scene.objects if o.name.startswith("Guides")]
    assert len(guides) == 1, [o.name for o in bpy.context.scene.objects]
    for frame, hidden in ((1, False), (2, True), (3, False)):
        for key in ("hide_viewport", "hide_render"):
            setattr(guides[0], key, hidden)
            guides[0].keyframe_insert(key, frame=frame)
    bpy.ops.wm.alembic_export(filepath=out, start=1, end=3, evaluation_mode="VIEWPORT")


main()
