// Scene sections for organs in their environment: pressure loads, rigid obstacles and
// contacts between deformable objects, read against the parameter table.
#pragma once

#include <string>
#include <vector>

#include "io/scene_reader.hpp"
#include "phymul/scene.hpp"

namespace phymul::io {

// An object name written in the scene, checked against the objects once all are read.
struct ObjectReference {
  std::string name;
  SourceLoc loc;
  std::string where;
};

// The `cylinder` of a pressure load (read whatever the type: the table's conditions skip it).
void read_pressure_cylinder(SectionReader& reader, PressureSpec& spec);

// One entry of `obstacles` / `contacts`; the object names go to `references`.
ObstacleSpec read_obstacle(SectionReader& reader, std::vector<ObjectReference>& references);
ContactSpec read_contact(SectionReader& reader, std::vector<ObjectReference>& references);
// One entry of `needles`: its tissues' and target's object names go to `references`.
NeedleSpec read_needle(SectionReader& reader, std::vector<ObjectReference>& references);

}  // namespace phymul::io
