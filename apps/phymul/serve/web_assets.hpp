// The page's files, a fixed set read once at start from share/phymul/web (built by CMake
// with esbuild): a request names one of them or gets 404, never a path on disk.
#pragma once

#include <map>
#include <string>

namespace phymul::serve {

struct WebAsset {
  std::string content_type, body;
};

struct WebAssets {
  std::map<std::string, WebAsset> files;  // by URL path: "/", "/app.js"
  bool built = false;                     // false: the page was not built (no npm); "/" says so
};

WebAssets load_web_assets();

}  // namespace phymul::serve
