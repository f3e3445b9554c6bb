#include "web_assets.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "phymul/installation.hpp"

namespace phymul::serve {
namespace {

bool read(const std::filesystem::path& p, std::string& into) {
  std::ifstream in(p, std::ios::binary);
  if (!in) return false;
  std::stringstream s;
  s << in.rdbuf();
  into = s.str();
  return true;
}

// What "/" shows when the build had no npm to fetch three.js with.
constexpr const char* kNotBuilt = R"(<!doctype html><meta charset="utf-8"><title>phymul</title>
<p>The live view's page was not built: npm or esbuild was missing when phymul was built
(see docs/live-view.md). The simulation runs, and its WebSocket at <code>/ws</code> answers.</p>
)";

}  // namespace

WebAssets load_web_assets() {
  WebAssets a;
  std::filesystem::path dir;
  try {
    dir = share_directory() / "web";
  } catch (const std::exception&) {
    dir.clear();
  }
  WebAsset index{"text/html; charset=utf-8", ""}, app{"text/javascript; charset=utf-8", ""};
  if (!dir.empty() && read(dir / "index.html", index.body) && read(dir / "app.js", app.body)) {
    a.files["/"] = index;
    a.files["/index.html"] = index;
    a.files["/app.js"] = app;
    a.built = true;
  } else {
    a.files["/"] = {"text/html; charset=utf-8", kNotBuilt};
  }
  return a;
}

}  // namespace phymul::serve
