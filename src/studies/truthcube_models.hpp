// Pieces shared by the Truth Cube study's two models.
#pragma once

#include "phymul/studies/truthcube.hpp"

namespace phymul::truthcube {

struct Plates {
  std::vector<int> base;   // nodes on the fixed face
  std::vector<int> plate;  // nodes on the pushed face
  // With sliding plates, rigid motion in x, y and about z is stopped by holding the base
  // centre in x and y, and a base node on the centre's x line in y.
  int centre = -1;
  int on_x_line = -1;
};
Plates plate_nodes(const Mesh& mesh, const CubeFrame& frame);

void run_fem(const Study& study, const std::vector<Bead>& beads, const StudyOptions& options,
             const Embedding& embedding, std::vector<LevelResult>& out);

}  // namespace phymul::truthcube
