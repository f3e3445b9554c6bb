#!/usr/bin/env python3
"""Writes examples/meshes/block.msh (Gmsh 4.1 ASCII, physical groups bottom, top, block) and
block.vtk (the same hexahedra, legacy VTK ASCII), in millimetres: a 40 x 40 x 20 mm block."""
import os

NX, NY, NZ = 6, 6, 3
SIZE = (40.0, 40.0, 20.0)
here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples", "meshes")


def node(i, j, k):
    return i + (NX + 1) * (j + (NY + 1) * k)


points = [(SIZE[0] * i / NX - SIZE[0] / 2, SIZE[1] * j / NY - SIZE[1] / 2, SIZE[2] * k / NZ)
          for k in range(NZ + 1) for j in range(NY + 1) for i in range(NX + 1)]
hexes = [[node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k), node(i, j + 1, k),
          node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)]
         for k in range(NZ) for j in range(NY) for i in range(NX)]
def face(k):
    return [[node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k), node(i, j + 1, k)]
            for j in range(NY) for i in range(NX)]


fmt = lambda v: repr(float(v))
with open(os.path.join(here, "block.msh"), "w") as f:
    f.write("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n")
    f.write('$PhysicalNames\n3\n2 1 "bottom"\n2 2 "top"\n3 3 "block"\n$EndPhysicalNames\n')
    f.write("$Entities\n0 0 2 1\n")
    f.write("1 -20 -20 0 20 20 0 1 1 0\n2 -20 -20 20 20 20 20 1 2 0\n")
    f.write("1 -20 -20 0 20 20 20 1 3 2 1 2\n$EndEntities\n")
    n = len(points)
    f.write(f"$Nodes\n1 {n} 1 {n}\n3 1 0 {n}\n")
    f.writelines(f"{t + 1}\n" for t in range(n))
    f.writelines(" ".join(map(fmt, p)) + "\n" for p in points)
    f.write("$EndNodes\n")
    bottom, top = face(0), face(NZ)
    total = len(bottom) + len(top) + len(hexes)
    f.write(f"$Elements\n3 {total} 1 {total}\n")
    tag = 1
    for dim, entity, etype, cells in [(2, 1, 3, bottom), (2, 2, 3, top), (3, 1, 5, hexes)]:
        f.write(f"{dim} {entity} {etype} {len(cells)}\n")
        for c in cells:
            f.write(f"{tag} " + " ".join(str(v + 1) for v in c) + "\n")
            tag += 1
    f.write("$EndElements\n")

with open(os.path.join(here, "block.vtk"), "w") as f:
    f.write("# vtk DataFile Version 4.2\n40 x 40 x 20 mm block (mm)\nASCII\n")
    f.write(f"DATASET UNSTRUCTURED_GRID\nPOINTS {len(points)} double\n")
    f.writelines(" ".join(map(fmt, p)) + "\n" for p in points)
    f.write(f"CELLS {len(hexes)} {9 * len(hexes)}\n")
    f.writelines("8 " + " ".join(map(str, c)) + "\n" for c in hexes)
    f.write(f"CELL_TYPES {len(hexes)}\n")
    f.writelines("12\n" for _ in hexes)
