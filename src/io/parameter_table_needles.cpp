// The scene fields of needles (docs/needles.md), part of the parameter table.
#include "io/parameter_table.hpp"

namespace phymul::io {

namespace {
Range gt(double min) { return {min, std::nullopt, true, false}; }
Range ge(double min) { return {min, std::nullopt, false, false}; }
}  // namespace

std::vector<Parameter> needle_parameters() {
  return {
      {.section = "needle",
       .name = "name",
       .kind = Kind::name,
       .default_note = "`needle<index>`",
       .doc = "Name of the needle's columns in monitors.csv and of its punctures in "
              "report.json."},
      {.section = "needle",
       .name = "base",
       .kind = Kind::vector,
       .dimension = Dimension::length,
       .required = true,
       .doc = "Where the tip is at depth 0 (the entry of the guide); the shaft runs from here "
              "to the tip."},
      {.section = "needle",
       .name = "direction",
       .kind = Kind::vector,
       .required = true,
       .doc = "Direction of insertion, from base to tip. Any non-zero length."},
      {.section = "needle",
       .name = "depth",
       .kind = Kind::scalar_schedule,
       .dimension = Dimension::length,
       .required = true,
       .doc = "Tip depth along the direction from the base over time: a length, or {t, value} "
              "events (linear between them); a decreasing depth retracts it."},
      {.section = "needle",
       .name = "radius",
       .kind = Kind::quantity,
       .dimension = Dimension::length,
       .range = gt(0),
       .default_value = "0.5 mm",
       .doc = "Shaft radius, for display (an 18 G biopsy needle: 0.6 mm)."},
      {.section = "needle",
       .name = "spacing",
       .kind = Kind::quantity,
       .dimension = Dimension::length,
       .range = gt(0),
       .default_value = "1 mm",
       .doc = "Tip travel between two points of the track embedded in the tissue; of the order "
              "of the mesh's edge or less."},
      {.section = "needle",
       .name = "tissues",
       .kind = Kind::list,
       .range = ge(1),
       .required = true,
       .child = "needle_tissue",
       .doc = "The objects it may puncture, each with its parameters."},
      {.section = "needle",
       .name = "target",
       .kind = Kind::map,
       .default_note = "none",
       .child = "needle_target",
       .doc = "A point aimed at, moving with its object."},
      {.section = "needle_tissue",
       .name = "object",
       .kind = Kind::name,
       .required = true,
       .doc = "Name of a deformable volume object (tetrahedra, hexahedra or wedges)."},
      {.section = "needle_tissue",
       .name = "puncture_force",
       .kind = Kind::quantity,
       .dimension = Dimension::force,
       .range = ge(0),
       .required = true,
       .doc = "Push of the tip on the surface at which it breaks through."},
      {.section = "needle_tissue",
       .name = "friction",
       .kind = Kind::quantity,
       .dimension = Dimension::stiffness,
       .range = ge(0),
       .default_value = "0",
       .doc = "Kinetic friction along the shaft per inserted length (N/m); the tissue sticks to "
              "the shaft below it."},
      {.section = "needle_tissue",
       .name = "cutting_force",
       .kind = Kind::quantity,
       .dimension = Dimension::force,
       .range = ge(0),
       .default_value = "0",
       .doc = "Force on the tissue at the tip while the tip advances in it."},
      {.section = "needle_target",
       .name = "object",
       .kind = Kind::name,
       .required = true,
       .doc = "Name of the volume object the target moves with."},
      {.section = "needle_target",
       .name = "point",
       .kind = Kind::vector,
       .dimension = Dimension::length,
       .required = true,
       .doc = "The target at rest, inside the object."},
  };
}

}  // namespace phymul::io
