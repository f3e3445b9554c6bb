// Meshes read from files: legacy VTK ASCII unstructured grids (.vtk, versions up to 5.1),
// VTK XML unstructured grids (.vtu), Gmsh ASCII (.msh, versions 4.1 and 2.2) and closed
// surfaces (.stl, .obj, .ply, VTK XML PolyData .vtp). Every problem names the file, its line
// and column where it has lines (for VTK XML: the element's), what was expected and what was
// found.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "phymul/mesh.hpp"

namespace phymul {

class MeshFileError : public std::runtime_error {
 public:
  MeshFileError(std::string file, int line, int column, std::string message);
  std::string file;
  int line, column;  // 1-based; 0 when the problem is the file as a whole
  std::string message;
};

// Coordinates are divided by `divisor` (1000 for a file in millimetres), so that "4" in mm
// gives exactly the double nearest 0.004, as the scene's units do.
//
// Cells: triangle, quad, tetra, hexahedron, wedge (VTK order; Gmsh prisms are reordered to
// VTK's wedge). All volume or all surface: a VTK file mixing them is refused; in a Gmsh file
// the cells of the highest dimension are the mesh and the lower ones (boundary triangles,
// lines, points) only define node sets. Gmsh physical groups become node sets named as in
// $PhysicalNames ("physical_<tag>" without a name). Points that no cell uses are refused.
//
// Closed surfaces (an organ's boundary, as segmentation tools write them): STL (ASCII or
// binary), OBJ (polygons split into triangles from their first vertex), PLY (ASCII or binary,
// either byte order), VTP (its Polys, split likewise; vertices, lines and strips are refused).
// Points with the same coordinates are merged; the surface must be closed, manifold, orientable,
// free of degenerate and crossing triangles (a MeshFileError names the edges or triangles
// otherwise); its orientation is made consistent and outward. What was repaired is appended to
// `notes`.
Mesh read_mesh_file(const std::filesystem::path& path, double divisor = 1.0,
                    std::vector<std::string>* notes = nullptr);

// The same, from text; `name` is used in messages.
Mesh parse_vtk_mesh(std::string_view text, const std::string& name, double divisor = 1.0);
Mesh parse_gmsh_mesh(std::string_view text, const std::string& name, double divisor = 1.0);
Mesh parse_stl_mesh(std::string_view bytes, const std::string& name, double divisor = 1.0,
                    std::vector<std::string>* notes = nullptr);
Mesh parse_obj_mesh(std::string_view text, const std::string& name, double divisor = 1.0,
                    std::vector<std::string>* notes = nullptr);
Mesh parse_ply_mesh(std::string_view bytes, const std::string& name, double divisor = 1.0,
                    std::vector<std::string>* notes = nullptr);
// VTK XML (one Piece; ASCII, base64 or appended arrays, plain or zlib-compressed): an
// unstructured grid as a legacy VTK file, and a PolyData surface's polygons as a closed surface.
Mesh parse_vtu_mesh(std::string_view bytes, const std::string& name, double divisor = 1.0);
Mesh parse_vtp_mesh(std::string_view bytes, const std::string& name, double divisor = 1.0,
                    std::vector<std::string>* notes = nullptr);

}  // namespace phymul
