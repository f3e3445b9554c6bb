#include <fmt/format.h>

#include <iostream>
#include <memory>

#include "commands.hpp"
#include "phymul/camitk.hpp"
#include "phymul/scene_io.hpp"

namespace phymul::cli {
namespace {

struct Settings {
  std::string scene, output;
};

int export_pml(const Settings& s) {
  try {
    const Scene scene = load_scene(s.scene);
    const PmlExport e = phymul::export_pml(scene, s.output);
    std::cout << fmt::format("{}: {} objects written to {} and {} (mm, N, kPa)\n", s.scene,
                             scene.objects.size(), e.pml.string(), e.lml.string());
    for (const std::string& note : e.notes) std::cout << "  note: " << note << '\n';
    return 0;
  } catch (const SceneError& e) {  // every problem of the scene, then exit 1
    for (const Diagnostic& d : e.diagnostics()) std::cerr << d.str() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

Command add_export_pml_command(CLI::App& parent) {
  auto settings = std::make_shared<Settings>();
  CLI::App* app = parent.add_subcommand(
      "export-pml", "write a scene's objects as a CamiTK PML model and its loads as LML");
  app->add_option("scene", settings->scene, "scene file (YAML)")->required();
  app->add_option("-o,--output", settings->output, "directory for <scene>.pml and <scene>.lml")
      ->required();
  return {app, [settings] { return export_pml(*settings); }};
}

}  // namespace phymul::cli
