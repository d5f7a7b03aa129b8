#!/usr/bin/env python3
"""Writes grooms/meshes/head_lowpoly.obj: a low-poly stand-in for coif's analytic head (the
ellipsoid of src/head.rs, semi-axes 7.8 x 10 x 9.5 cm at the origin) as a closed, outward-oriented
UV ellipsoid, for recipes' `shape = "mesh"` obstacles. Regenerate with
    python3 scripts/make_head_mesh.py grooms/meshes/head_lowpoly.obj
"""
import math
import sys

RADII = (0.078, 0.100, 0.095)
RINGS, SEGMENTS = 16, 32


def main(path):
    vertices = [(0.0, RADII[1], 0.0)]
    for r in range(1, RINGS):
        theta = math.pi * r / RINGS
        for s in range(SEGMENTS):
            phi = 2.0 * math.pi * s / SEGMENTS
            unit = (math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi))
            vertices.append(tuple(u * a for u, a in zip(unit, RADII)))
    vertices.append((0.0, -RADII[1], 0.0))
    bottom = len(vertices) - 1

    def ring(r, s):
        return 1 + (r - 1) * SEGMENTS + s % SEGMENTS

    faces = []
    for s in range(SEGMENTS):
        faces.append((0, ring(1, s + 1), ring(1, s)))
        faces.append((bottom, ring(RINGS - 1, s), ring(RINGS - 1, s + 1)))
    for r in range(1, RINGS - 1):
        for s in range(SEGMENTS):
            a, b, c, d = ring(r, s), ring(r, s + 1), ring(r + 1, s), ring(r + 1, s + 1)
            faces.append((a, b, d))
            faces.append((a, d, c))
    # Every face must point away from the centre (the field's sign depends on it).
    for f in faces:
        p = [vertices[i] for i in f]
        e1 = [p[1][k] - p[0][k] for k in range(3)]
        e2 = [p[2][k] - p[0][k] for k in range(3)]
        n = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
        centroid = [sum(q[k] for q in p) / 3.0 for k in range(3)]
        assert sum(n[k] * centroid[k] for k in range(3)) > 0.0, f"face {f} points inwards"
    with open(path, "w") as out:
        out.write("# coif's analytic head as a low-poly UV ellipsoid (scripts/make_head_mesh.py)\n")
        out.write(f"# {len(vertices)} vertices, {len(faces)} triangles, metres, Y up, face towards +Z\n")
        out.write("o head_lowpoly\n")
        for v in vertices:
            out.write("v {:.6f} {:.6f} {:.6f}\n".format(*v))
        for f in faces:
            out.write("f {} {} {}\n".format(*(i + 1 for i in f)))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "grooms/meshes/head_lowpoly.obj")
