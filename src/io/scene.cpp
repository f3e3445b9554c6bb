// Scene files: YAML text -> Scene, checked field by field against the parameter table.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "io/parameter_table.hpp"
#include "io/scene_interactions.hpp"
#include "io/scene_reader.hpp"
#include "phymul/nifti.hpp"
#include "phymul/scene_io.hpp"

namespace phymul {

namespace {

using io::SceneContext;
using io::SectionReader;

// A scene is a few kilobytes; refusing huge files keeps a wrong path from eating memory.
constexpr std::uintmax_t kMaxSceneBytes = 64u << 20;

std::string join_lines(const std::vector<Diagnostic>& diagnostics) {
  std::string out;
  for (const auto& diagnostic : diagnostics) {
    if (!out.empty()) out += '\n';
    out += diagnostic.str();
  }
  return out;
}

// Length of the UTF-8 sequence at text[i], 0 when it is not valid UTF-8 (overlong forms
// and surrogates included).
size_t utf8_length(const std::string& text, size_t i) {
  const auto byte = [&](size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char c = byte(i);
  if (c < 0x80) return 1;
  size_t length = 0;
  unsigned char low = 0x80, high = 0xBF;  // allowed range of the second byte
  if (c >= 0xC2 && c <= 0xDF) {
    length = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    length = 3;
    if (c == 0xE0) low = 0xA0;
    if (c == 0xED) high = 0x9F;
  } else if (c >= 0xF0 && c <= 0xF4) {
    length = 4;
    if (c == 0xF0) low = 0x90;
    if (c == 0xF4) high = 0x8F;
  } else {
    return 0;
  }
  if (i + length > text.size()) return 0;
  if (byte(i + 1) < low || byte(i + 1) > high) return 0;
  for (size_t k = 2; k < length; ++k)
    if ((byte(i + k) & 0xC0) != 0x80) return 0;
  return length;
}

// yaml-cpp accepts or garbles NUL bytes, control characters and invalid UTF-8; a binary
// file deserves one clear message instead.
bool check_text(SceneContext& context, const std::string& text) {
  int line = 1, column = 1;
  for (size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    const size_t length = utf8_length(text, i);
    const bool control = c < 0x20 && c != '\t' && c != '\n' && c != '\r';
    if (length == 0 || control || c == 0x7F) {
      context.error(
          {context.file(), line, column},
          fmt::format("scene file is not YAML text (byte 0x{:02x}{}); is it a binary file?", c,
                      length == 0 ? " is not valid UTF-8" : " is a control character"));
      return false;
    }
    if (c == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
    i += length;
  }
  return true;
}

std::string top_level_keys() {
  std::string keys;
  for (const auto* parameter : io::section_parameters("scene"))
    keys += fmt::format("{}{}:", keys.empty() ? "" : ", ", parameter->name);
  return keys;
}

// Sees the document stream without building it, to notice yaml-cpp 0.7 looping on stray flow
// punctuation (a lone ',' yields empty documents forever: yaml-cpp issue #1040).
class DocumentCounter : public YAML::EventHandler {
 public:
  YAML::Mark last;
  void OnDocumentStart(const YAML::Mark& mark) override { last = mark; }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t,
                const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
};

// False (with where it stalled) when the parser would hand out documents without end: every
// real document consumes at least one character.
bool document_stream_ends(const std::string& text, YAML::Mark& stall) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  DocumentCounter counter;
  for (size_t documents = 0; documents <= text.size() + 1; ++documents)
    if (!parser.HandleNextDocument(counter)) return true;
  stall = counter.last;
  return false;
}

std::optional<YAML::Node> load_yaml(SceneContext& context, const std::string& text) {
  if (!check_text(context, text)) return std::nullopt;
  std::vector<YAML::Node> documents;
  try {
    YAML::Mark stall;
    if (!document_stream_ends(text, stall)) {
      context.error(context.loc(stall),
                    "YAML syntax error: stray flow punctuation (such as a lone ',') outside any "
                    "[list] or {map}");
      return std::nullopt;
    }
    documents = YAML::LoadAll(text);
  } catch (const YAML::DeepRecursion& e) {
    context.error(context.loc(e.mark), "YAML nesting is too deep");
    return std::nullopt;
  } catch (const YAML::Exception& e) {
    context.error(context.loc(e.mark), fmt::format("YAML syntax error: {}", e.msg));
    return std::nullopt;
  }
  if (documents.empty() || (documents.size() == 1 && documents[0].IsNull())) {
    context.error({context.file(), 0, 0},
                  fmt::format("scene file is empty (expected a map with {})", top_level_keys()));
    return std::nullopt;
  }
  if (documents.size() > 1) {
    context.error(
        context.loc(documents[1]),
        fmt::format("scene file holds {} YAML documents; it must hold one", documents.size()));
    return std::nullopt;
  }
  if (!documents[0].IsMap()) {
    context.error(context.loc(documents[0]),
                  fmt::format("the top level of a scene must be a map with {} (got {})",
                              top_level_keys(), io::describe_node(documents[0])));
    return std::nullopt;
  }
  return documents[0];
}

// Fills the Scene structs from checked sections, and remembers object names and the
// references to them for the cross-checks that need the whole file.
class SceneBuilder {
 public:
  explicit SceneBuilder(SceneContext& context) : context_(context) {}

  Scene build(const YAML::Node& root, const std::string& file);

 private:
  struct Named {  // an object name or a reference to one, where it was written
    std::string name;
    SourceLoc loc;
    std::string where;
  };

  SimulationSpec simulation(SectionReader& reader);
  ObjectSpec object(SectionReader& reader);
  MeshSpec mesh(SectionReader& reader);
  void check_mesh_source(SectionReader& reader);
  MeshTransform mesh_transform(SectionReader& reader);
  void check_label_image(SectionReader& reader, const MeshSpec& spec);
  MaterialSpec material(SectionReader& reader);
  void load(SectionReader& reader, Scene& scene);
  ConstraintSpec constraint(SectionReader& reader);
  LinkSpec link(SectionReader& reader);
  void object_kind(SectionReader& reader, ObjectSpec& spec);
  void elastic_material(const MaterialSpec& material);
  FibreSpec fibres(SectionReader& reader);
  OutputSpec output(SectionReader& reader);
  void refer(SectionReader& reader, std::string_view key, const std::string& object);
  void check_names();
  void check_references();

  // Where the current object's material gives these, valid or not: what else it then needs.
  struct MaterialGiven {
    std::optional<SourceLoc> stiffness, young, poisson, calibration_axis;
  };

  SceneContext& context_;
  MaterialGiven material_given_;
  bool material_model_known_ = true;  // the last material's `model` was absent or valid
  std::vector<Named> names_;
  std::vector<Named> references_;
  size_t objects_ = 0;  // including those whose name is invalid
};

Scene SceneBuilder::build(const YAML::Node& root, const std::string& file) {
  Scene scene;
  scene.file = file;
  SectionReader top(context_, root, "scene", "the top level", context_.loc(root));
  if (auto reader = top.map("simulation")) scene.simulation = simulation(*reader);
  top.items("objects", [&](SectionReader& r) { scene.objects.push_back(object(r)); });
  objects_ = scene.objects.size();
  top.items("loads", [&](SectionReader& r) { load(r, scene); });
  top.items("constraints", [&](SectionReader& r) { scene.constraints.push_back(constraint(r)); });
  top.items("stitches", [&](SectionReader& r) { scene.stitches.push_back(link(r)); });
  top.items("doubled", [&](SectionReader& r) { scene.doubled.push_back(link(r)); });
  std::vector<io::ObjectReference> interactions;
  top.items("obstacles", [&](SectionReader& r) {
    scene.obstacles.push_back(io::read_obstacle(r, interactions));
  });
  top.items("contacts",
            [&](SectionReader& r) { scene.contacts.push_back(io::read_contact(r, interactions)); });
  top.items("needles",
            [&](SectionReader& r) { scene.needles.push_back(io::read_needle(r, interactions)); });
  for (auto& reference : interactions)
    references_.push_back({reference.name, reference.loc, reference.where});
  if (auto reader = top.map("output")) scene.output = output(*reader);
  if (std::string lml; top.read("lml", lml)) scene.lml = LmlSpec{lml, false, *top.value_loc("lml")};
  top.done();
  check_names();
  check_references();
  return scene;
}

SimulationSpec SceneBuilder::simulation(SectionReader& reader) {
  SimulationSpec spec;
  spec.loc = reader.loc();
  reader.read_fields(spec);
  spec.integrator_loc = reader.value_loc("integrator").value_or(SourceLoc{});
  spec.solver_loc = reader.value_loc("solver").value_or(SourceLoc{});
  reader.done();
  return spec;
}

ObjectSpec SceneBuilder::object(SectionReader& reader) {
  ObjectSpec spec;
  spec.loc = reader.loc();
  reader.read_fields(spec);
  if (reader.given("name"))
    names_.push_back({spec.name, *reader.value_loc("name"), reader.where()});
  if (auto mesh_reader = reader.map("mesh")) spec.mesh = mesh(*mesh_reader);
  material_given_ = {};
  if (auto material_reader = reader.map("material")) spec.material = material(*material_reader);
  object_kind(reader, spec);
  reader.done();
  return spec;
}

// What the object's type adds (motion, fibres) and the fields it refuses or needs.
void SceneBuilder::object_kind(SectionReader& reader, ObjectSpec& spec) {
  const bool has_type = !reader.value_loc("type") || reader.given("type");  // absent: elastic
  const bool has_motion = reader.value_loc("motion").has_value();
  if (auto motion = reader.map("motion"); motion && has_motion) {
    MotionSpec m;
    m.loc = motion->loc();
    motion->read_fields(m);
    motion->done();
    spec.motion = std::move(m);
  }
  if (auto fibre_reader = reader.map("fibres")) spec.fibres = fibres(*fibre_reader);
  if (!has_type) return;
  if (spec.type == ObjectType::rigid) {
    if (const auto& at = material_given_.stiffness)
      context_.error(*at,
                     "'stiffness' applies only to elastic and active objects "
                     "(this object is rigid)");
    if (const auto& at = material_given_.young)
      context_.error(*at,
                     "'young' applies only to elastic and active objects (this object is rigid)");
    if (spec.volume_constraint)
      context_.error(reader.value_loc("volume_constraint").value_or(reader.loc()),
                     "'volume_constraint' applies only to elastic and active objects (this "
                     "object is rigid)");
  } else if (material_model_known_ && reader.value_loc("material") && spec.material.loc.line > 0) {
    elastic_material(spec.material);
  }
}

// Which of stiffness, young and poisson an elastic material needs: finite elements take E
// and nu; shape memory takes K, or E and nu to calibrate K on.
void SceneBuilder::elastic_material(const MaterialSpec& m) {
  const MaterialGiven& given = material_given_;
  if (m.model == ElasticModel::fem) {
    for (auto [key, at] : {std::pair{"young", given.young}, {"poisson", given.poisson}})
      if (!at) context_.error(m.loc, fmt::format("'{}' is required in 'material'", key));
    return;
  }
  if (given.stiffness && given.young)
    context_.error(*given.young,
                   "give only one of 'stiffness' (K) or 'young' (K calibrated from it) in "
                   "'material'");
  else if (!given.stiffness && !given.young)
    context_.error(m.loc,
                   "'stiffness' is required in 'material' (or 'young' and 'poisson', to "
                   "calibrate it against finite elements)");
  if (given.young && !given.poisson)
    context_.error(m.loc,
                   "'poisson' is required with 'young' in 'material' (the finite elements K is "
                   "calibrated on)");
  if (!given.young)
    for (auto [key, at] :
         {std::pair{"poisson", given.poisson}, {"calibration_axis", given.calibration_axis}})
      if (at)
        context_.error(*at, fmt::format("'{}' applies to a shape-memory material only with "
                                        "'young' (K calibrated from it)",
                                        key));
}

FibreSpec SceneBuilder::fibres(SectionReader& reader) {
  FibreSpec spec;
  spec.loc = reader.loc();
  if (reader.read("direction", spec.direction) && spec.direction.cwiseAbs().maxCoeff() == 0.0)
    context_.error(reader.value_loc("direction").value_or(reader.loc()),
                   "'direction' must be a non-zero vector (got [0, 0, 0])");
  reader.read_fields(spec);
  Schedule activation;
  bool ok = true;
  reader.items("activation", [&](SectionReader& event) {
    double t = 0.0, a = 0.0;
    const bool has_t = event.read("t", t), has_a = event.read("a", a);
    event.done();
    if (!has_t || !has_a) {
      ok = false;
      return;
    }
    if (!activation.times.empty() && t <= activation.times.back()) {
      context_.error(event.value_loc("t").value_or(event.loc()),
                     fmt::format("activation times must be strictly increasing: {} has t = {} s "
                                 "after t = {} s",
                                 event.where(), t, activation.times.back()));
      ok = false;
      return;
    }
    activation.times.push_back(t);
    activation.values.push_back(Eigen::Vector3d(a, 0.0, 0.0));
  });
  if (ok) spec.activation = std::move(activation);
  reader.done();
  return spec;
}

LinkSpec SceneBuilder::link(SectionReader& reader) {
  LinkSpec spec;
  spec.loc = reader.loc();
  reader.read_fields(spec);
  refer(reader, "object", spec.object);
  refer(reader, "with", spec.with);
  reader.done();
  return spec;
}

MeshSpec SceneBuilder::mesh(SectionReader& reader) {
  MeshSpec spec;
  spec.loc = reader.loc();
  reader.read_fields(spec);
  spec.fill_tetra = reader.value_loc("fill").has_value();
  std::string fill;
  reader.read("fill", fill);
  if (spec.fill_tetra && !reader.value_loc("edge"))
    context_.error(*reader.value_loc("fill"),
                   "'fill' needs 'edge', the largest edge of the tetrahedra (a length)");
  if (auto transform = reader.map("transform")) spec.transform = mesh_transform(*transform);
  check_mesh_source(reader);
  check_label_image(reader, spec);
  reader.done();
  return spec;
}

MeshTransform SceneBuilder::mesh_transform(SectionReader& reader) {
  MeshTransform t;
  reader.read_fields(t);
  if (auto rotate = reader.map("rotate")) {
    Eigen::Vector3d axis = t.axis;
    if (rotate->read("axis", axis) && axis.cwiseAbs().maxCoeff() == 0.0)
      context_.error(rotate->value_loc("axis").value_or(rotate->loc()),
                     "'axis' of 'rotate' must be a non-zero vector (got [0, 0, 0])");
    else
      t.axis = axis.stableNormalized();
    rotate->read_fields(t);
    rotate->done();
  }
  reader.done();
  return t;
}

// A label image needs its labels and its filling; a surface or mesh file takes no labels.
void SceneBuilder::check_label_image(SectionReader& reader, const MeshSpec& spec) {
  const auto file = reader.value_loc("file");
  if (!file) return;
  const bool image = is_nifti_path(spec.file);
  if (!image) {
    if (const auto at = reader.value_loc("labels"))
      context_.error(*at, "'labels' applies to a label image file (.nii, .nii.gz) only");
    return;
  }
  if (!reader.value_loc("labels"))
    context_.error(*file,
                   "a label image needs 'labels', the labels that make the object "
                   "(e.g. labels: [1, 2])");
  if (!spec.fill_tetra)
    context_.error(*file,
                   "a label image needs 'fill: tetra' and 'edge': its labels become a "
                   "surface of that edge, filled with tetrahedra");
  if (const auto at = reader.value_loc("units"))
    context_.error(*at,
                   "'units' does not apply to a label image: its header gives its frame's "
                   "unit");
  if (const auto at = reader.value_loc("remesh"))
    context_.error(*at,
                   "'remesh' does not apply to a label image: 'edge' sets its surface's "
                   "triangles");
}

// A mesh from a file takes only `units`; the generators' keys would be silently ignored.
void SceneBuilder::check_mesh_source(SectionReader& reader) {
  const bool from_file = reader.value_loc("file").has_value();
  for (const io::Parameter* p : io::section_parameters("mesh")) {
    if (p->name == "generator" || p->name == "transform") continue;  // one_of: names both
    const bool generator_key = p->name != "file" && p->name != "units" && p->name != "fill" &&
                               p->name != "edge" && p->name != "remesh" && p->name != "component" &&
                               p->name != "labels";
    if (from_file == generator_key)
      if (const auto at = reader.value_loc(p->name))
        context_.error(*at, from_file ? fmt::format("'{}' belongs to generated meshes; a mesh "
                                                    "read from 'file' takes only 'units', "
                                                    "'transform', 'remesh', 'fill' and 'edge'",
                                                    p->name)
                                      : fmt::format("'{}' applies only to a mesh read from "
                                                    "'file'",
                                                    p->name));
  }
}

MaterialSpec SceneBuilder::material(SectionReader& reader) {
  MaterialSpec spec;
  spec.loc = reader.loc();
  reader.read_fields(spec);
  // An invalid `model` requires nothing; what is given decides what else is required.
  material_model_known_ = !reader.value_loc("model") || reader.given("model");
  material_given_ = {reader.value_loc("stiffness"), reader.value_loc("young"),
                     reader.value_loc("poisson"), reader.value_loc("calibration_axis")};
  spec.young_loc = reader.value_loc("young").value_or(SourceLoc{});
  spec.law_loc = reader.value_loc("law").value_or(SourceLoc{});
  spec.hexa_loc = reader.value_loc("hexa").value_or(SourceLoc{});
  reader.done();
  return spec;
}

// Remembers a valid object name `key` refers to, checked once every object is read.
void SceneBuilder::refer(SectionReader& reader, std::string_view key, const std::string& object) {
  if (reader.given(key)) references_.push_back({object, *reader.value_loc(key), reader.where()});
}

// A nodal force or a pressure: every field is read whatever the type (the table's
// conditions skip those that do not apply), then the entry goes to its list.
void SceneBuilder::load(SectionReader& reader, Scene& scene) {
  LoadSpec spec;
  spec.loc = reader.loc();
  std::string type;
  reader.read("type", type);
  reader.read_fields(spec);
  refer(reader, "object", spec.object);
  PressureSpec pressure;
  reader.read_fields(pressure);
  io::read_pressure_cylinder(reader, pressure);
  reader.done();
  if (type == "pressure") {
    pressure.object = spec.object;
    pressure.nodes = spec.nodes;
    pressure.loc = spec.loc;
    scene.pressures.push_back(std::move(pressure));
  } else {
    scene.loads.push_back(std::move(spec));
  }
}

ConstraintSpec SceneBuilder::constraint(SectionReader& reader) {
  ConstraintSpec spec;
  spec.loc = reader.loc();
  reader.read_fields(spec);
  refer(reader, "object", spec.object);
  reader.done();
  // A fixed node is a zero displacement on every axis; spelling it out lets later stages
  // treat both kinds alike.
  if (spec.kind == ConstraintSpec::Kind::fixed)
    spec.displacement = Schedule::constant(Eigen::Vector3d::Zero());
  return spec;
}

OutputSpec SceneBuilder::output(SectionReader& reader) {
  OutputSpec spec;
  spec.loc = reader.loc();
  reader.read_fields(spec);
  reader.done();
  return spec;
}

void SceneBuilder::check_names() {
  std::map<std::string, SourceLoc> first;
  for (const auto& named : names_) {
    const auto [previous, inserted] = first.emplace(named.name, named.loc);
    if (!inserted)
      context_.error(named.loc, fmt::format("object name '{}' is used twice (first at line {})",
                                            named.name, previous->second.line));
  }
}

void SceneBuilder::check_references() {
  std::vector<std::string_view> known;
  for (const auto& named : names_)
    if (std::find(known.begin(), known.end(), named.name) == known.end())
      known.push_back(named.name);
  for (const auto& reference : references_) {
    if (std::find(known.begin(), known.end(), reference.name) != known.end()) continue;
    std::string hint;
    if (const auto suggestion = closest_match(reference.name, known))
      hint = fmt::format("did you mean '{}'? ", *suggestion);
    const std::string list = !known.empty()
                                 ? fmt::format("known objects: {}", fmt::join(known, ", "))
                             : objects_ > 0 ? "no object has a valid name"
                                            : "no objects are defined";
    context_.error(reference.loc, fmt::format("{} refers to unknown object '{}' ({}{})",
                                              reference.where, reference.name, hint, list));
  }
}

std::optional<std::string> read_file(const std::filesystem::path& file, std::string& text) {
  const auto failure = [&](std::string_view reason) {
    return fmt::format("cannot read scene file '{}': {}", file.string(), reason);
  };
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) return failure(std::strerror(EISDIR));
  errno = 0;
  std::ifstream in(file, std::ios::binary);
  if (!in) return failure(errno != 0 ? std::strerror(errno) : "cannot open");
  const auto size = std::filesystem::file_size(file, ec);
  if (!ec && size > kMaxSceneBytes)
    return failure(fmt::format("larger than {} MiB; is it a scene?", kMaxSceneBytes >> 20));
  std::ostringstream content;
  content << in.rdbuf();
  if (in.bad()) return failure(errno != 0 ? std::strerror(errno) : "read error");
  text = content.str();
  return std::nullopt;
}

}  // namespace

std::string Diagnostic::str() const {
  const std::string prefix = loc.file.empty() ? "" : loc.file + ":";
  if (loc.line <= 0) return prefix.empty() ? message : fmt::format("{} {}", prefix, message);
  if (loc.column <= 0) return fmt::format("{}{}: {}", prefix, loc.line, message);
  return fmt::format("{}{}:{}: {}", prefix, loc.line, loc.column, message);
}

SceneError::SceneError(std::vector<Diagnostic> diagnostics)
    : std::runtime_error(join_lines(diagnostics)), diagnostics_(std::move(diagnostics)) {}

Scene read_scene_text(const std::string& text, const std::string& file_name) {
  SceneContext context(file_name);
  Scene scene;
  scene.file = file_name;
  try {
    if (const auto root = load_yaml(context, text))
      scene = SceneBuilder(context).build(*root, file_name);
  } catch (const YAML::Exception& e) {
    // Node access should not throw once parsing succeeded; report rather than crash.
    context.error(context.loc(e.mark), fmt::format("cannot read the scene: {}", e.msg));
  }
  if (!context.ok()) throw SceneError(context.sorted_diagnostics());
  return scene;
}

Scene parse_scene(const std::string& text, const std::string& file_name) {
  Scene scene = read_scene_text(text, file_name);
  prepare_scene(scene);
  return scene;
}

Scene load_scene(const std::filesystem::path& file) {
  std::string text;
  if (auto problem = read_file(file, text)) throw SceneError({Diagnostic{{}, std::move(*problem)}});
  return parse_scene(text, file.string());
}

}  // namespace phymul
