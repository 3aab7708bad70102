#!/usr/bin/env python3
"""gen_ring.py: writes ring.obj, the thick short tube of the ring-caustics scenes.

The ring is a closed triangle mesh in its own object space, standing on the
y = 0 plane with its axis along +y (Mitsuba's usual "up"):

    outer wall   radius R, smooth outward normals ( cos a, 0,  sin a)
    inner wall   radius r = R - t, smooth inward normals (-cos a, 0, -sin a)
    top annulus  y = h, flat normal (0, 1, 0), between r and R
    bottom       y = 0, flat normal (0, -1, 0), between r and R

Each of the n segments (angle a_i = 2 pi i / n) contributes one quad per part,
written as two triangles. Triangles wind counter-clockwise seen from the side
their normal points to, so the geometric normal (v1 - v0) x (v2 - v0) agrees
with the vertex normals and points out of the solid. Positions are shared
between the walls and the annuli (OBJ indexes positions and normals
separately), so the mesh is watertight; the sharp rims come from the separate
normals.

Before writing, the script checks its own output: every directed edge
appears once and its reverse once (closed, consistently oriented two-
manifold), every triangle's geometric normal has a positive dot product with
its three vertex normals, and the signed volume of the mesh matches the
polygonal tube's exact volume n/2 sin(2 pi/n) (R^2 - r^2) h.

Numbers are written with 6 significant digits to keep the file small.
Usage: python3 gen_ring.py [--segments 256] [--radius 1] [--thickness 0.06]
       [--height 0.5] [-o ring.obj]   (default output: beside this script)
"""

import argparse
import math
import os
import sys


def fmt(x):
    """A number with 6 significant digits, without a negative zero."""
    s = "%.6g" % x
    return "0" if s in ("-0", "0") else s


def build(n, big_r, thick, height):
    """Returns (positions, normals, triangles); triangles hold (p, n) index pairs (0-based)."""
    small_r = big_r - thick
    pos = []
    # Position layout: for segment i, four points at indices 4i + k:
    # k = 0 outer bottom, 1 outer top, 2 inner bottom, 3 inner top.
    for i in range(n):
        a = 2.0 * math.pi * i / n
        c, s = math.cos(a), math.sin(a)
        pos.append((big_r * c, 0.0, big_r * s))
        pos.append((big_r * c, height, big_r * s))
        pos.append((small_r * c, 0.0, small_r * s))
        pos.append((small_r * c, height, small_r * s))
    nrm = []
    # Normal layout: 2i outward radial, 2i + 1 inward radial, then up, down.
    for i in range(n):
        a = 2.0 * math.pi * i / n
        c, s = math.cos(a), math.sin(a)
        nrm.append((c, 0.0, s))
        nrm.append((-c, 0.0, -s))
    up, down = 2 * n, 2 * n + 1
    nrm.append((0.0, 1.0, 0.0))
    nrm.append((0.0, -1.0, 0.0))

    tris = []
    for i in range(n):
        j = (i + 1) % n
        ob0, ot0, ib0, it0 = 4 * i, 4 * i + 1, 4 * i + 2, 4 * i + 3
        ob1, ot1, ib1, it1 = 4 * j, 4 * j + 1, 4 * j + 2, 4 * j + 3
        no0, no1 = 2 * i, 2 * j
        ni0, ni1 = 2 * i + 1, 2 * j + 1
        # Outer wall, seen from outside: the angle grows from +x toward +z,
        # which is clockwise seen from outside when y is up, so go
        # bottom(i) -> top(i) -> top(j) for a counter-clockwise order.
        tris.append(((ob0, no0), (ot0, no0), (ot1, no1)))
        tris.append(((ob0, no0), (ot1, no1), (ob1, no1)))
        # Inner wall, seen from the axis: the opposite order.
        tris.append(((ib0, ni0), (ib1, ni1), (it1, ni1)))
        tris.append(((ib0, ni0), (it1, ni1), (it0, ni0)))
        # Top annulus, seen from above (+y).
        tris.append(((it0, up), (it1, up), (ot1, up)))
        tris.append(((it0, up), (ot1, up), (ot0, up)))
        # Bottom annulus, seen from below (-y).
        tris.append(((ib0, down), (ob0, down), (ob1, down)))
        tris.append(((ib0, down), (ob1, down), (ib1, down)))
    return pos, nrm, tris


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def check(pos, nrm, tris, n, big_r, thick, height):
    """Returns a list of problems (empty: the mesh is fine)."""
    problems = []
    edges = {}
    for t in tris:
        for k in range(3):
            e = (t[k][0], t[(k + 1) % 3][0])
            edges[e] = edges.get(e, 0) + 1
    for (a, b), count in edges.items():
        if count != 1 or edges.get((b, a), 0) != 1:
            problems.append("edge %d-%d: used %d times, reverse %d times"
                            % (a, b, count, edges.get((b, a), 0)))
            break
    bad = 0
    volume = 0.0
    for t in tris:
        p0, p1, p2 = (pos[c[0]] for c in t)
        g = cross(sub(p1, p0), sub(p2, p0))
        for c in t:
            if dot(g, nrm[c[1]]) <= 0.0:
                bad += 1
        # Signed volume of the tetrahedron (origin, p0, p1, p2).
        volume += dot(p0, cross(p1, p2)) / 6.0
    if bad:
        problems.append("%d triangle corners whose normal disagrees with the winding" % bad)
    small_r = big_r - thick
    exact = 0.5 * n * math.sin(2.0 * math.pi / n) * (big_r ** 2 - small_r ** 2) * height
    if abs(volume - exact) > 1e-9 * max(1.0, exact):
        problems.append("signed volume %.9g, expected %.9g" % (volume, exact))
    return problems


def write(path, pos, nrm, tris, args):
    with open(path, "w") as f:
        f.write("# ring.obj, written by gen_ring.py: a closed tube, axis +y, standing on y = 0\n")
        f.write("# segments %d, outer radius %s, thickness %s, height %s\n"
                % (args.segments, fmt(args.radius), fmt(args.thickness), fmt(args.height)))
        for p in pos:
            f.write("v %s %s %s\n" % (fmt(p[0]), fmt(p[1]), fmt(p[2])))
        for q in nrm:
            f.write("vn %s %s %s\n" % (fmt(q[0]), fmt(q[1]), fmt(q[2])))
        for t in tris:
            f.write("f %s\n" % " ".join("%d//%d" % (c[0] + 1, c[1] + 1) for c in t))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description="Write the ring mesh of the ring-caustics scenes.")
    ap.add_argument("--segments", type=int, default=256)
    ap.add_argument("--radius", type=float, default=1.0, help="outer radius")
    ap.add_argument("--thickness", type=float, default=0.06, help="wall thickness")
    ap.add_argument("--height", type=float, default=0.5)
    ap.add_argument("-o", "--output", default=os.path.join(here, "ring.obj"))
    args = ap.parse_args()
    if args.segments < 3 or not 0.0 < args.thickness < args.radius or args.height <= 0.0:
        sys.exit("gen_ring.py: need segments >= 3, 0 < thickness < radius, height > 0")
    pos, nrm, tris = build(args.segments, args.radius, args.thickness, args.height)
    problems = check(pos, nrm, tris, args.segments, args.radius, args.thickness, args.height)
    if problems:
        sys.exit("gen_ring.py: " + "; ".join(problems))
    write(args.output, pos, nrm, tris, args)
    print("%s: %d positions, %d normals, %d triangles"
          % (args.output, len(pos), len(nrm), len(tris)))


if __name__ == "__main__":
    main()
