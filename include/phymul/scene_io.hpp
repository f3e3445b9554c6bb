// Scene files: the YAML a user writes, parsed and checked against the scene schema into a
// Scene ready to compile (its mesh files read, shape-memory stiffness calibrated from
// Young's modulus where a scene gives `young`).
#pragma once

#include <filesystem>
#include <string>

#include "phymul/scene.hpp"

namespace phymul {

// Parses and checks a scene file; throws SceneError listing every problem (unreadable file,
// YAML syntax, unknown key with did-you-mean, wrong type, value out of range, missing
// required field, a mesh file that cannot be read, a calibration that fails), each at its
// file, line and column.
Scene load_scene(const std::filesystem::path& file);
// The same for scene text; `file_name` names it in messages, and mesh file paths are
// relative to its directory.
Scene parse_scene(const std::string& text, const std::string& file_name);

// What load_scene does after parsing, for a scene built or edited in a program: reads each
// object's mesh file into MeshSpec::file_mesh (a mesh already read is kept) and calibrates
// the stiffness of shape-memory objects given `young` (calibration.hpp). SceneError with
// every problem.
void prepare_scene(Scene& scene);

// The scene reference (Markdown), generated from the schema.
std::string scene_reference_markdown();

}  // namespace phymul
