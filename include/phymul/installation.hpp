// The files phymul ships beside its program: the measured data (Truth Cube beads) and the
// picture scripts of the studies.
#pragma once

#include <filesystem>

namespace phymul {

// <prefix>/share/phymul for a program installed in <prefix>/bin (or any sibling directory of
// bin: a build tree's bench/), else share/phymul beside the running program (a build tree's
// own copy). Found from the program's own path, never from where it was built;
// std::runtime_error naming both places when neither exists.
std::filesystem::path share_directory();

}  // namespace phymul
