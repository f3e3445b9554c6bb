#include "phymul/installation.hpp"

#include <fmt/format.h>

#include <stdexcept>
#include <system_error>

namespace phymul {

std::filesystem::path share_directory() {
  std::error_code ec;
  // Linux: the running program's own path.
  const std::filesystem::path program = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find the running program's path (/proc/self/exe)");
  const std::filesystem::path installed = program.parent_path().parent_path() / "share" / "phymul";
  const std::filesystem::path beside = program.parent_path() / "share" / "phymul";
  for (const std::filesystem::path& candidate : {installed, beside})
    if (std::filesystem::is_directory(candidate, ec)) return candidate;
  throw std::runtime_error(
      fmt::format("phymul's shared files are missing: neither {} nor {} exists (reinstall, or "
                  "rebuild: the build copies them into its share/phymul)",
                  installed.string(), beside.string()));
}

}  // namespace phymul
