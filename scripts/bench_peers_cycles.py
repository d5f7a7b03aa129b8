"""Cycles' side of `make bench-peers`: a worker that builds the benchmark shot once in Blender
(bpy, run with .deps/bpy-venv/bin/python) and then renders it on request, so the BVH and kernels
are built once and only render time is measured (persistent data, as a turntable keeps them).

    bench_peers_cycles.py SHOT.json

SHOT.json (written by scripts/bench_peers.py) names an .npz of the strands' cubic B-spline control
points and radii, and the camera, key light, dome, pigment, roughness, bounces and resolution.
Requests come one per stdin line, `SPP SEED OUT.exr`; each is answered by one stdout line,
`bench-peers-cycles {"seconds": render time}` (Blender prints lines of its own), once OUT.exr
(linear RGBA) is written. One untimed 1-spp render at start-up syncs the scene and builds the
BVH, which persistent data then keeps.

The shot as Cycles gets it:
- Curves: Cycles traces every curve as round Catmull-Rom pieces through its points. The strands'
  uniform B-splines are evaluated at every quarter knot (more densely towards the ends) and given
  as Catmull-Rom curves through those points; the largest distance between the two curves is
  printed on stderr at start-up, in fibre radii (0.34 on the benchmark's wavy groom; 1.2 with
  points every half knot).
- Pigment as an absorption coefficient (Principled Hair, Chiang model, "Absorption coefficient"
  parametrisation): Cycles' melanin parametrisation maps melanin to absorption with other
  coefficients than coif and Mitsuba (pbrt's), so σ_a itself is handed over.
- The key light as a sun of the same irradiance and angular diameter, the dome as a constant
  world colour, a 1-pixel box filter, no clamping, no glossy filter, no adaptive sampling, no
  denoising, 2 threads. `max_bounces = MAX_BOUNCES - 1`: coif's `--max-depth 8` and Mitsuba's
  `max_depth 9` both allow 8 scattering vertices, and Cycles counts bounces after the first.
"""
import json
import math
import os
import sys
import time

import bpy
import numpy as np
from mathutils import Matrix, Vector

REPLY = "bench-peers-cycles "
# Knot-parameter step of the Catmull-Rom points inside a strand; halvings towards its ends.
INNER_STEP, END_HALVINGS = 0.25, 5


def bspline_at(control, u):
    """Points of the uniform cubic B-spline with these control points at parameters `u` in
    [0, spans] (span i runs from u = i to i + 1 over control points i..i+3)."""
    spans = len(control) - 3
    i = np.minimum(np.floor(u).astype(int), spans - 1)
    t = (u - i)[:, None]
    weights = [(1 - t) ** 3 / 6, (3 * t**3 - 6 * t**2 + 4) / 6, (-3 * t**3 + 3 * t**2 + 3 * t + 1) / 6, t**3 / 6]
    return sum(w * control[i + k] for k, w in enumerate(weights))


def through_parameters(spans):
    """Where Cycles' Catmull-Rom curve passes through the B-spline: every INNER_STEP of a knot
    span, and at steps halving towards the ends, where the Catmull-Rom curve's repeated end point
    bends it away (halving, not one jump to fine steps: uneven steps bend it too)."""
    ends = np.array([0.0] + [INNER_STEP / 2.0**k for k in range(END_HALVINGS, 0, -1)])
    inner = np.arange(INNER_STEP, spans - INNER_STEP / 2, INNER_STEP)
    return np.unique(np.concatenate([ends, inner, spans - ends]))


def catmull_rom_points(points, steps):
    """Points of the Catmull-Rom curve through `points` (end points repeated, as Cycles does),
    `steps` per piece."""
    padded = np.concatenate([points[:1], points, points[-1:]])
    out = []
    for i in range(len(points) - 1):
        p0, p1, p2, p3 = padded[i : i + 4]
        for k in range(steps):
            t = k / steps
            out.append(
                0.5
                * (
                    2 * p1
                    + (-p0 + p2) * t
                    + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t * t
                    + (-p0 + 3 * p1 - 3 * p2 + p3) * t * t * t
                )
            )
    out.append(points[-1])
    return np.array(out)


def look_at(position, target):
    """A camera matrix looking from `position` at `target`, world +Y up (coif's space)."""
    eye, forward = Vector(position), (Vector(target) - Vector(position)).normalized()
    right = forward.cross(Vector((0.0, 1.0, 0.0))).normalized()
    up = right.cross(forward)
    m = Matrix.Identity(4)
    for row in range(3):
        m[row][0], m[row][1], m[row][2], m[row][3] = right[row], up[row], -forward[row], eye[row]
    return m


def build(shot):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    data = np.load(shot["curves"])
    counts, control, radii = data["counts"], data["points"], data["radii"]

    curves = bpy.data.hair_curves.new("groom")
    per_strand, positions, widths, deviation = [], [], [], 0.0
    start = 0
    for n in counts:
        c, r = control[start : start + n], radii[start : start + n]
        u = through_parameters(n - 3)
        through = bspline_at(c, u)
        per_strand.append(len(through))
        positions.append(through)
        widths.append(bspline_at(r[:, None], u)[:, 0])
        if len(per_strand) % 499 == 1:  # a sample of strands for the printout
            # From points along the Catmull-Rom curve to the nearest of dense B-spline points.
            fine = catmull_rom_points(through, 8)
            dense = bspline_at(c, np.linspace(0.0, n - 3, (n - 3) * 256 + 1))
            nearest = np.sqrt(((fine[:, None, :] - dense[None, :, :]) ** 2).sum(-1)).min(axis=1)
            deviation = max(deviation, float(nearest.max() / r.mean()))
        start += n
    curves.add_curves(per_strand)
    curves.set_types(type="CATMULL_ROM")
    curves.position_data.foreach_set("vector", np.concatenate(positions).astype(np.float32).ravel())
    radius = curves.attributes.get("radius") or curves.attributes.new("radius", "FLOAT", "POINT")
    radius.data.foreach_set("value", np.concatenate(widths).astype(np.float32))
    print(
        f"cycles: {len(counts)} strands as Catmull-Rom through {sum(per_strand)} points; largest distance"
        f" to the B-splines {deviation:.3f} fibre radii (sampled strands)",
        file=sys.stderr,
        flush=True,
    )
    groom = bpy.data.objects.new("groom", curves)
    scene.collection.objects.link(groom)

    material = bpy.data.materials.new("hair")
    material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.clear()
    hair = nodes.new("ShaderNodeBsdfHairPrincipled")
    hair.model, hair.parametrization = "CHIANG", "ABSORPTION"
    hair.inputs["Absorption Coefficient"].default_value = shot["sigma_a"]
    hair.inputs["Roughness"].default_value = shot["beta_m"]
    hair.inputs["Radial Roughness"].default_value = shot["beta_n"]
    hair.inputs["Coat"].default_value = 0.0
    hair.inputs["IOR"].default_value = shot["ior"]
    hair.inputs["Offset"].default_value = math.radians(shot["alpha_degrees"])
    for name in ["Random Color", "Random Roughness"]:  # no random variation (absent in some modes)
        if name in hair.inputs:
            hair.inputs[name].default_value = 0.0
    output = nodes.new("ShaderNodeOutputMaterial")
    material.node_tree.links.new(hair.outputs["BSDF"], output.inputs["Surface"])
    curves.materials.append(material)

    world = bpy.data.worlds.new("dome")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (*[shot["dome_radiance"]] * 3, 1.0)
    background.inputs["Strength"].default_value = 1.0
    scene.world = world

    sun_data = bpy.data.lights.new("key", "SUN")
    sun_data.energy = shot["key_irradiance"]
    sun_data.angle = math.radians(shot["key_angle_degrees"])
    sun = bpy.data.objects.new("key", sun_data)
    # A sun shines along its local -Z: its +Z points towards the light.
    sun.rotation_euler = Vector(shot["key_direction"]).normalized().to_track_quat("Z", "Y").to_euler()
    scene.collection.objects.link(sun)

    camera_data = bpy.data.cameras.new("camera")
    camera_data.sensor_fit = "VERTICAL"
    camera_data.angle_y = math.radians(shot["fov"])
    camera_data.clip_start, camera_data.clip_end = 1e-3, 100.0
    camera = bpy.data.objects.new("camera", camera_data)
    camera.matrix_world = look_at(shot["camera_position"], shot["camera_target"])
    scene.collection.objects.link(camera)
    scene.camera = camera

    render = scene.render
    render.engine = "CYCLES"
    render.resolution_x, render.resolution_y = shot["width"], shot["height"]
    render.resolution_percentage = 100
    render.threads_mode, render.threads = "FIXED", shot["threads"]
    render.use_persistent_data = True
    render.hair_type = "CYLINDER"
    render.image_settings.file_format = "OPEN_EXR"
    render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.pixel_filter_type, cycles.filter_width = "BOX", 1.0
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    cycles.blur_glossy = 0.0
    bounces = shot["max_bounces"] - 1
    cycles.max_bounces = bounces
    cycles.diffuse_bounces = cycles.glossy_bounces = cycles.transmission_bounces = bounces
    cycles.transparent_max_bounces = shot["max_bounces"]
    cycles.use_animated_seed = False
    return scene


def render(scene, spp, seed, path):
    """Seconds to render and write `path` (a 32-bit EXR: a few milliseconds of them). Saving the
    "Render Result" image after rendering instead writes a stale one in background mode."""
    scene.cycles.samples = spp
    scene.cycles.seed = seed
    scene.render.filepath = path
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - start


def main():
    shot = json.load(open(sys.argv[1]))
    scene = build(shot)
    warm_up = shot["curves"] + ".warm-up.exr"
    render(scene, 1, 9_999, warm_up)
    os.remove(warm_up)
    for line in sys.stdin:
        spp, seed, path = line.split()
        spp, seed = int(spp), int(seed)
        seconds = render(scene, spp, seed, path)
        print(REPLY + json.dumps({"seconds": seconds}), flush=True)


if __name__ == "__main__":
    main()
