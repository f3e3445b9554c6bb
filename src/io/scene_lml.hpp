// Internal to scene preparation: a scene's CamiTK LML loads (Scene::lml) turned into its loads,
// constraints and pressures (docs/camitk.md).
#pragma once

#include <vector>

#include "phymul/scene.hpp"

namespace phymul::io {

// Once per scene (LmlSpec::applied): each LML load becomes, for every object read from the PML
// file that holds some of its atoms, a constraint (Translation), a load (Force, on the first
// such object only, so that stitched objects do not get it twice) or a pressure (Pressure).
// Problems are appended, each at its line of the LML file; what phymul does differently from
// CamiTK goes to Scene::notes.
void apply_lml(Scene& scene, std::vector<Diagnostic>& problems);

}  // namespace phymul::io
