// phymul: soft organs simulated with their surroundings (the Phymul model). One header for
// the library; the studies (Truth Cube, prostate) have theirs under phymul/studies/.
//
//   phymul::Scene scene = phymul::load_scene("scene.yaml");   // scene_io.hpp
//   const phymul::Model model = phymul::compile_scene(scene);  // model.hpp
//   phymul::Data data = phymul::make_data(model);              // simulation.hpp
//   for (int k = 0; k < 1000; ++k) phymul::step(model, data);  // data.x: positions (m)
#pragma once

#include "phymul/calibration.hpp"
#include "phymul/camitk.hpp"
#include "phymul/checkpoint.hpp"
#include "phymul/data.hpp"
#include "phymul/fem.hpp"
#include "phymul/forces.hpp"
#include "phymul/mesh.hpp"
#include "phymul/mesh_io.hpp"
#include "phymul/meshing.hpp"
#include "phymul/model.hpp"
#include "phymul/results.hpp"
#include "phymul/run.hpp"
#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/scene_words.hpp"
#include "phymul/schedule.hpp"
#include "phymul/schema.hpp"
#include "phymul/simulation.hpp"
#include "phymul/vtk.hpp"
