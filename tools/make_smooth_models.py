#!/usr/bin/env python3
"""Writes the low-polygon meshes with vertex normals (OBJ `vn`) used by
scenes/smooth.json: a torus and a twisted vase, each a grid of quads whose
corners carry the exact surface normal. Facets alone show their edges;
smooth shading (--smooth) interpolates the normals across each facet.

    python3 tools/make_smooth_models.py scenes/models
"""
import math
import os
import sys


def write_grid(path, title, nu, nv, point, normal, closed_v):
    """Quads over a (u, v) grid, u wrapping around; v wraps when closed_v."""
    rows = nv if closed_v else nv + 1
    with open(path, "w") as out:
        out.write("# %s: %d x %d quads with vertex normals (tools/make_smooth_models.py)\n" % (title, nu, nv))
        out.write("o %s\n" % title)
        for j in range(rows):
            for i in range(nu):
                out.write("v %.6f %.6f %.6f\n" % point(i / nu, j / nv))
        for j in range(rows):
            for i in range(nu):
                n = normal(i / nu, j / nv)
                length = math.sqrt(sum(c * c for c in n))
                out.write("vn %.6f %.6f %.6f\n" % tuple(c / length for c in n))
        for j in range(nv):
            for i in range(nu):
                a = j * nu + i + 1
                b = j * nu + (i + 1) % nu + 1
                c = ((j + 1) % rows) * nu + (i + 1) % nu + 1
                d = ((j + 1) % rows) * nu + i + 1
                # Counter-clockwise seen from outside (the normal's side).
                out.write("f %d//%d %d//%d %d//%d %d//%d\n" % (a, a, d, d, c, c, b, b))


def torus(directory):
    big, small = 1.0, 0.38

    def point(u, v):
        a, b = 2 * math.pi * u, 2 * math.pi * v
        return ((big + small * math.cos(b)) * math.cos(a), small * math.sin(b), (big + small * math.cos(b)) * math.sin(a))

    def normal(u, v):
        a, b = 2 * math.pi * u, 2 * math.pi * v
        return (math.cos(b) * math.cos(a), math.sin(b), math.cos(b) * math.sin(a))

    write_grid(os.path.join(directory, "torus.obj"), "torus", 24, 12, point, normal, True)


def vase(directory):
    # A surface of revolution r(h), h in [0, 1], open at the top.
    def radius(h):
        return 0.45 + 0.25 * math.sin(math.pi * (1.6 * h + 0.1)) + 0.08 * h

    def slope(h):
        return 0.25 * math.pi * 1.6 * math.cos(math.pi * (1.6 * h + 0.1)) + 0.08

    height = 1.8

    def point(u, v):
        a, r = 2 * math.pi * u, radius(v)
        return (r * math.cos(a), height * v, r * math.sin(a))

    def normal(u, v):
        # Outward normal of a surface of revolution: (cos a, -dr/dy, sin a).
        a = 2 * math.pi * u
        return (math.cos(a), -slope(v) / height, math.sin(a))

    write_grid(os.path.join(directory, "vase.obj"), "vase", 20, 10, point, normal, False)


if __name__ == "__main__":
    folder = sys.argv[1] if len(sys.argv) > 1 else "scenes/models"
    os.makedirs(folder, exist_ok=True)
    torus(folder)
    vase(folder)
