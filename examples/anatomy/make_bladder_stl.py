#!/usr/bin/env python3
"""Writes bladder_segmented.stl beside itself: a bladder wall as a segmentation pipeline gives
it, far too fine and irregular for shape memory (5120 triangles of 1 to 3 mm, each vertex moved
by up to 0.4 mm), in millimetres, binary STL. bladder_from_stl.yaml reads it and remeshes it.
Usage: /usr/bin/python3 examples/anatomy/make_bladder_stl.py"""
import os
import struct

import numpy as np

RADII = np.array([34.0, 30.0, 26.0])  # mm: a bladder of about 110 mL, flattened top to bottom
rng = np.random.default_rng(7)

# An icosahedron subdivided four times, projected on the unit sphere.
t = (1 + 5 ** 0.5) / 2
points = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
          (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
points = [np.array(p, float) / np.linalg.norm(p) for p in points]
faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
for _ in range(4):
    middle = {}

    def mid(a, b):
        key = (min(a, b), max(a, b))
        if key not in middle:
            p = points[a] + points[b]
            points.append(p / np.linalg.norm(p))
            middle[key] = len(points) - 1
        return middle[key]

    faces = [f for a, b, c in faces
             for f in ((a, mid(a, b), mid(c, a)), (b, mid(b, c), mid(a, b)),
                       (c, mid(c, a), mid(b, c)), (mid(a, b), mid(b, c), mid(c, a)))]
unit = np.array(points)
xyz = unit * RADII * (1 + rng.uniform(-0.4, 0.4, (len(unit), 1)) / RADII.mean())

with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "bladder_segmented.stl"),
          "wb") as f:
    f.write(b"bladder wall, as segmented: fine and irregular".ljust(80, b" "))
    f.write(struct.pack("<I", len(faces)))
    for a, b, c in faces:
        n = np.cross(xyz[b] - xyz[a], xyz[c] - xyz[a])
        n /= np.linalg.norm(n)
        f.write(struct.pack("<12fH", *n, *xyz[a], *xyz[b], *xyz[c], 0))
