"""Writes the Blender test grooms in tests/data/ with Blender's own hair node-group assets and
its own Alembic and USD exporters (bpy 5.0.1, installed by scripts/check_blender_setup.sh):

  .deps/bpy-venv/bin/python scripts/make_test_grooms_blender.py tests/data

(or `make test-grooms-blender`). What an artist's file looks like (production-grooms.md):

- a closed head mesh `Head` (UV sphere, its UV map), modelled in metres (Blender's default
  units), Z up. Alembic in metres (Y up, as Alembic always is; `global_scale` would scale the
  points but not the radii, and Alembic has no unit field), USD in centimetres as for Maya or
  Unreal: `convert_scene_units` CENTIMETERS (`metersPerUnit` 0.01, a scale of 100 on the root
  Xform, `upAxis` "Z");
- guides: a Curves object `Guides` on the head, scattered by the 'Generate Hair Curves' asset
  over the scalp (a density mask on the head), then combed down over the head in this script
  and resampled to 5–9 points per strand, Catmull-Rom;
- children: a Curves object `Hair` made from the guides by the 'Interpolate Hair Curves' asset
  (applied), resampled to 4–10 points per strand, POLY (linear);
- radii tapering from root to tip (40 µm to 20 µm).

Files (small: tens of KB):
  blender_groom.abc / .usda / .usdc   static, head radius 10 cm
  blender_groom_anim.abc / .usda      the same with the head (the hair's parent) nodding over
                                      frames 1-5 at 24 fps: transform-only animation
  blender_groom_x2.abc / .usda        everything twice as large (head radius 20 cm)

`blender_grooms.json` records what Blender itself holds for each file before export (curves and
points per object, the head mesh's vertices and faces, the head radius): the tests' independent
expectation for counts.

Blender's scatter is random but seeded; the files are checked in and this script is how they
were made, not something tests run.
"""
import json
import math
import os
import sys

import bpy
from mathutils import Vector

HEAD_RADIUS_M = 0.1
FPS = 24
ANIM_FRAMES = (1, 5)


def assets():
    path = os.path.join(bpy.utils.system_resource("DATAFILES"), "assets", "nodes", "procedural_hair_node_assets.blend")
    with bpy.data.libraries.load(path) as (_, into):
        into.node_groups = ["Generate Hair Curves", "Interpolate Hair Curves"]


def inputs(group):
    return {i.name: i.identifier for i in group.interface.items_tree if i.item_type == "SOCKET" and i.in_out == "INPUT"}


def apply_modifier(obj, name):
    with bpy.context.temp_override(object=obj, active_object=obj, selected_objects=[obj]):
        bpy.ops.object.modifier_apply(modifier=name)


def new_hair(head, name):
    """An empty hair object on the head, as Add > Curves > Empty Hair makes it."""
    with bpy.context.temp_override(active_object=head, object=head, selected_objects=[head]):
        bpy.ops.object.curves_empty_hair_add()
    hair = bpy.context.view_layer.objects.active
    for modifier in list(hair.modifiers):
        hair.modifiers.remove(modifier)  # the surface-deform modifier: the head is not deformed
    hair.name = name
    hair.data.name = name + "Data"
    return hair


def node_modifier(obj, group_name, values, masks=()):
    modifier = obj.modifiers.new(group_name, "NODES")
    modifier.node_group = bpy.data.node_groups[group_name]
    ids = inputs(modifier.node_group)
    for key, value in values.items():
        modifier[ids[key]] = value
    for key, attribute in masks:
        modifier[ids[key] + "_use_attribute"] = True
        modifier[ids[key] + "_attribute_name"] = attribute
    return modifier


def polyline(curves, c):
    start = curves.curve_offset_data[c].value
    count = curves.curves[c].points_length
    return [Vector(curves.points[start + i].position) for i in range(count)]


def resample(points, count):
    """`count` points evenly spaced by arc length along a polyline."""
    lengths = [0.0]
    for a, b in zip(points, points[1:]):
        lengths.append(lengths[-1] + (b - a).length)
    out = []
    for k in range(count):
        s = lengths[-1] * k / (count - 1)
        i = max(j for j in range(len(points) - 1) if lengths[j] <= s + 1e-9) if s > 0 else 0
        i = min(i, len(points) - 2)
        span = lengths[i + 1] - lengths[i]
        t = 0.0 if span == 0 else (s - lengths[i]) / span
        out.append(points[i].lerp(points[i + 1], min(max(t, 0.0), 1.0)))
    return out


def comb(root, length, radius):
    """A strand combed down over a spherical head: out along the normal, then falling towards
    -Z, kept 4 % outside the head. 24 points, resampled later."""
    normal = root.normalized()
    down = Vector((0.0, 0.0, -1.0))
    step = length / 23
    points = [root.copy()]
    for k in range(1, 24):
        w = math.exp(-k / 3.0)
        direction = (normal * w + down * (1.0 - w)).normalized()
        p = points[-1] + direction * step
        if p.length < radius * 1.04:
            p = p.normalized() * radius * 1.04
        points.append(p)
    return resample(points, 24)


def set_curves(curves, strands, curve_type):
    """Replaces the curves' shapes (same curve count) with `strands`, resizing each curve."""
    curves.resize_curves(sizes=[len(s) for s in strands])
    flat = [p for s in strands for p in s]
    positions = curves.attributes["position"].data
    for i, p in enumerate(flat):
        positions[i].vector = p
    curves.set_types(type=curve_type)
    radius = curves.attributes.get("radius") or curves.attributes.new("radius", "FLOAT", "POINT")
    at = 0
    for s in strands:
        for k in range(len(s)):
            radius.data[at].value = 40e-6 - 20e-6 * k / (len(s) - 1)
            at += 1


def build(scale):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = FPS
    radius = HEAD_RADIUS_M * scale
    assets()

    bpy.ops.mesh.primitive_uv_sphere_add(segments=16, ring_count=10, radius=radius, location=(0, 0, 0))
    head = bpy.context.view_layer.objects.active
    head.name, head.data.name = "Head", "HeadMesh"
    mask = head.data.attributes.new("scalp", "FLOAT", "POINT")
    for i, v in enumerate(head.data.vertices):
        x, y, z = v.co / radius
        # The scalp: the top and back of the head, not the face (front is -Y in Blender).
        mask.data[i].value = 1.0 if z > 0.45 or (z > -0.3 and y > -0.2) else 0.0

    guides = new_hair(head, "Guides")
    node_modifier(
        guides,
        "Generate Hair Curves",
        {"Surface": head, "Hair Length": 1.0, "Control Points": 4, "Density": 320.0 / scale**2, "Seed": 7},
        masks=[("Density Mask", "scalp")],
    )
    apply_modifier(guides, "Generate Hair Curves")
    curves = guides.data
    strands = []
    for c in range(len(curves.curves)):
        root = polyline(curves, c)[0]
        length = radius * (3.6 + 1.0 * ((c * 7) % 5) / 4)
        strands.append(resample(comb(root, length, radius), 5 + (c % 5)))
    set_curves(curves, strands, "CATMULL_ROM")

    children = guides.copy()
    children.data = guides.data.copy()
    scene.collection.objects.link(children)
    children.name, children.data.name = "Hair", "HairData"
    node_modifier(
        children,
        "Interpolate Hair Curves",
        {"Surface": head, "Interpolation Guides": 3, "Density": 2600.0 / scale**2, "Seed": 5},
        masks=[("Density Mask", "scalp")],
    )
    apply_modifier(children, "Interpolate Hair Curves")
    curves = children.data
    strands = []
    for c in range(len(curves.curves)):
        points = polyline(curves, c)
        # Interpolation between guides can cut the head's curve: keep children outside too.
        points = [p if p.length >= radius * 1.02 or i == 0 else p.normalized() * radius * 1.02 for i, p in enumerate(points)]
        strands.append(resample(points, 4 + (c * 3) % 7))
    set_curves(curves, strands, "POLY")
    for hair in (guides, children):
        hair.parent = head
    return scene, head, guides, children


def animate(scene, head):
    """The head nods and turns (its hair follows as children): transform-only animation."""
    scene.frame_start, scene.frame_end = ANIM_FRAMES
    for frame in range(ANIM_FRAMES[0], ANIM_FRAMES[1] + 1):
        t = (frame - ANIM_FRAMES[0]) / (ANIM_FRAMES[1] - ANIM_FRAMES[0])
        head.location = (0.0, 0.0, 0.02 * t)
        head.rotation_euler = (math.radians(20.0 * t), 0.0, math.radians(-15.0 * t))
        head.keyframe_insert("location", frame=frame)
        head.keyframe_insert("rotation_euler", frame=frame)
    scene.frame_set(ANIM_FRAMES[0])


def export(out_dir, stem, animated, usdc=True):
    scene = bpy.context.scene
    frames = dict(start=scene.frame_start, end=scene.frame_end) if animated else dict(start=1, end=1)
    bpy.ops.wm.alembic_export(
        filepath=os.path.join(out_dir, stem + ".abc"),
        as_background_job=False,
        **frames,
    )
    extensions = (".usda",) if animated or not usdc else (".usda", ".usdc")
    for ext in extensions:
        bpy.ops.wm.usd_export(
            filepath=os.path.join(out_dir, stem + ext),
            export_animation=animated,
            convert_scene_units="CENTIMETERS",
        )


def record(head, guides, children, radius):
    """What Blender holds for one scene: counts per curve object and of the head mesh."""
    curves = lambda obj: dict(curves=len(obj.data.curves), points=len(obj.data.points))
    return dict(
        head_radius_m=radius,
        head=dict(vertices=len(head.data.vertices), faces=len(head.data.polygons)),
        Guides=curves(guides),
        Hair=curves(children),
    )


def main(out_dir):
    os.makedirs(out_dir, exist_ok=True)
    manifest = {}
    scene, head, guides, children = build(1.0)
    manifest["blender_groom"] = record(head, guides, children, HEAD_RADIUS_M)
    export(out_dir, "blender_groom", animated=False)
    animate(scene, head)
    export(out_dir, "blender_groom_anim", animated=True)
    manifest["blender_groom_anim"] = dict(manifest["blender_groom"])
    manifest["blender_groom_anim"]["frames"] = dict(start=ANIM_FRAMES[0], end=ANIM_FRAMES[1], fps=FPS)
    _, head, guides, children = build(2.0)
    manifest["blender_groom_x2"] = record(head, guides, children, 2.0 * HEAD_RADIUS_M)
    export(out_dir, "blender_groom_x2", animated=False, usdc=False)
    with open(os.path.join(out_dir, "blender_grooms.json"), "w") as f:
        json.dump(manifest, f, indent=2, sort_keys=True)
        f.write("\n")


if __name__ == "__main__":
    main(sys.argv[1])
