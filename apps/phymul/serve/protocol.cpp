#include "protocol.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "phymul/mesh.hpp"

namespace phymul::serve {
namespace {

using nlohmann::json;

// A refusal: parse_request turns it into an error reply.
struct Invalid {
  std::string message;
};

json vec(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

const char* shape_name(ObstacleShape s) {
  switch (s) {
    case ObstacleShape::plane:
      return "plane";
    case ObstacleShape::sphere:
      return "sphere";
    case ObstacleShape::capsule:
      return "capsule";
    case ObstacleShape::probe:
      return "probe";
  }
  return "?";
}

const char* kind_name(ObjectType t) {
  switch (t) {
    case ObjectType::elastic:
      return "elastic";
    case ObjectType::rigid:
      return "rigid";
    case ObjectType::active:
      return "active";
  }
  return "?";
}

std::string obstacle_name(const Model& m, size_t k) {
  return m.obstacles[k].name.empty() ? "obstacle" + std::to_string(k) : m.obstacles[k].name;
}

// The keys each operation takes besides "op" and "id".
const std::map<std::string, std::set<std::string>>& operations() {
  static const std::map<std::string, std::set<std::string>> ops = {
      {"play", {}},
      {"pause", {}},
      {"step", {"n"}},
      {"reset", {}},
      {"pace", {"value"}},
      {"drag", {"node", "target", "stiffness"}},
      {"release", {}},
      {"move_obstacle", {"obstacle", "offset", "translation"}},
      {"set_pressure", {"load", "value"}},
      {"set_target_volume", {"object", "value"}},
      {"set_force", {"node", "force"}},
      {"state", {"node"}},
  };
  return ops;
}

double number(const json& j, const char* key) {
  if (!j.contains(key)) throw Invalid{fmt::format("'{}' is required", key)};
  const json& v = j[key];
  if (!v.is_number()) throw Invalid{fmt::format("'{}' must be a number", key)};
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw Invalid{fmt::format("'{}' must be finite", key)};
  return x;
}

int integer(const json& j, const char* key, int lo, int hi) {
  if (!j.contains(key)) throw Invalid{fmt::format("'{}' is required", key)};
  const json& v = j[key];
  if (!v.is_number_integer() || v.get<long long>() < lo || v.get<long long>() > hi)
    throw Invalid{fmt::format("'{}' must be an integer in [{}, {}]", key, lo, hi)};
  return int(v.get<long long>());
}

Vec3 vector3(const json& j, const char* key, double most, const char* unit) {
  if (!j.contains(key)) throw Invalid{fmt::format("'{}' is required", key)};
  const json& v = j[key];
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
    throw Invalid{fmt::format("'{}' must be an array of 3 numbers ({})", key, unit)};
  const Vec3 x(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
  if (!x.allFinite() || x.norm() > most)
    throw Invalid{fmt::format("'{}' must be finite and at most {:g} {} long", key, most, unit)};
  return x;
}

// An entry named by its name or index among `count` (names from name_of).
template <class NameOf>
int entry(const json& j, const char* key, size_t count, NameOf name_of, const char* what) {
  if (!j.contains(key)) throw Invalid{fmt::format("'{}' is required", key)};
  const json& v = j[key];
  if (v.is_number_integer()) {
    const long long k = v.get<long long>();
    if (k < 0 || size_t(k) >= count)
      throw Invalid{fmt::format("no {} {} (the scene has {})", what, k, count)};
    return int(k);
  }
  if (v.is_string()) {
    for (size_t k = 0; k < count; ++k)
      if (name_of(k) == v.get<std::string>()) return int(k);
    throw Invalid{fmt::format("no {} named '{}'", what, v.get<std::string>())};
  }
  throw Invalid{fmt::format("'{}' must be a name or an index", key)};
}

int free_node(const json& j, const LiveSimulation& sim) {
  const Model& m = sim.model();
  const int node = integer(j, "node", 0, m.node_count() - 1);
  if (m.inverse_mass[size_t(node)].isZero())
    throw Invalid{fmt::format("node {} is held by a constraint: it cannot be moved", node)};
  return node;
}

Control control_of(const std::string& op, const json& j, const LiveSimulation& sim,
                   const std::vector<ObstacleSlide>& slides) {
  using Op = Control::Op;
  const Model& m = sim.model();
  const double size = m.size_scale;
  Control c;
  if (op == "play") c.op = Op::play;
  if (op == "pause") c.op = Op::pause;
  if (op == "reset") c.op = Op::reset;
  if (op == "release") c.op = Op::release;
  if (op == "step") {
    c.op = Op::step;
    c.count = j.contains("n") ? integer(j, "n", 1, 10000) : 1;
  }
  if (op == "pace") {
    c.op = Op::pace;
    const json& v = j.contains("value") ? j["value"] : json();
    if (v != "realtime" && v != "fast") throw Invalid{"'value' must be \"realtime\" or \"fast\""};
    c.pace = v == "fast" ? Pace::fast : Pace::realtime;
  }
  if (op == "drag") {
    c.op = Op::drag;
    c.index = free_node(j, sim);
    if (!(sim.drag_stiffness(c.index) > 0.0))
      throw Invalid{fmt::format("node {} has no elasticity to drag against", c.index)};
    c.vector = vector3(j, "target", 10 * size, "m");
    if ((c.vector - m.rest_position[size_t(c.index)]).norm() > size)
      throw Invalid{
          fmt::format("'target' is more than {:g} m (the scene's size) from the node", size)};
    c.value = j.contains("stiffness") ? number(j, "stiffness") : 0.0;
    if (c.value < 0.0) throw Invalid{"'stiffness' must be >= 0 N/m"};
  }
  if (op == "move_obstacle") {
    c.op = Op::move_obstacle;
    c.index = entry(
        j, "obstacle", m.obstacles.size(), [&](size_t k) { return obstacle_name(m, k); },
        "obstacle");
    const ObstacleSlide& s = slides[size_t(c.index)];
    if (j.contains("offset") == j.contains("translation"))
      throw Invalid{"give one of 'offset' (m along the slider) or 'translation' ([x, y, z] m)"};
    if (j.contains("offset")) {
      const double offset = number(j, "offset");
      if (offset < s.min || offset > s.max)
        throw Invalid{fmt::format("'offset' must be in [{:g}, {:g}] m", s.min, s.max)};
      c.vector = offset * s.direction;
    } else {
      c.vector = vector3(j, "translation", size, "m");
    }
  }
  if (op == "set_pressure") {
    c.op = Op::set_pressure;
    c.index = entry(
        j, "load", m.pressures.size(),
        [&](size_t k) { return m.components[size_t(m.pressures[k].component)].name; },
        "pressure load");
    c.value = number(j, "value");
    if (std::abs(c.value) > 1e6) throw Invalid{"'value' must be within +-1e6 Pa"};
  }
  if (op == "set_target_volume") {
    c.op = Op::set_target_volume;
    c.index = entry(
        j, "object", m.volumes.size(), [&](size_t k) { return m.volumes[k].component; },
        "volume constraint");
    c.value = number(j, "value");
    const double most = 100 * m.volumes[size_t(c.index)].target_volume;
    if (!(c.value > 0.0) || c.value > most)
      throw Invalid{fmt::format("'value' must be in (0, {:g}] m^3", most)};
  }
  if (op == "set_force") {
    c.op = Op::set_force;
    c.index = free_node(j, sim);
    c.vector = vector3(j, "force", 1e3, "N");
  }
  return c;
}

}  // namespace

DrawnSurface drawn_surface(const Model& model) {
  DrawnSurface s;
  for (const Component& c : model.components) {
    const int first = int(s.triangles.size());
    std::vector<Triangle> faces = c.boundary;
    if (faces.empty()) {  // an open surface: its cells, on the global points
      Mesh mesh;
      mesh.points = model.rest_position;
      for (int k = 0; k < c.cell_count; ++k)
        mesh.cells.push_back(model.cells[size_t(c.first_cell + k)]);
      faces = boundary_triangles(mesh);
    }
    s.triangles.insert(s.triangles.end(), faces.begin(), faces.end());
    s.range.push_back({first, int(faces.size())});
  }
  return s;
}

std::vector<ObstacleSlide> obstacle_slides(const Model& model) {
  std::vector<ObstacleSlide> slides;
  for (const RigidObstacle& o : model.obstacles) {
    ObstacleSlide s;
    Vec3 furthest = Vec3::Zero();
    for (const Vec3& v : o.motion.values)
      if (v.norm() > furthest.norm()) furthest = v;
    s.direction = furthest.norm() > 0.0 ? Vec3(furthest.normalized()) : o.axis;
    const double extent = std::max({2 * furthest.norm(), o.radius, 0.05 * model.size_scale});
    s.min = -extent;
    s.max = extent;
    slides.push_back(s);
  }
  return slides;
}

Request parse_request(const std::string& text, const LiveSimulation& sim,
                      const std::vector<ObstacleSlide>& slides) {
  Request r;
  if (text.size() > kMaxRequestBytes) {
    r.error =
        fmt::format("message too large ({} bytes; at most {})", text.size(), kMaxRequestBytes);
    return r;
  }
  const json j = json::parse(text, nullptr, false);
  if (j.is_discarded()) {
    r.error = "not JSON: send one JSON object, {\"op\": ...}";
    return r;
  }
  try {
    if (!j.is_object()) throw Invalid{"a message must be a JSON object, {\"op\": ...}"};
    if (j.contains("id")) {
      if (!j["id"].is_number_integer() && !j["id"].is_string())
        throw Invalid{"'id' must be an integer or a string"};
      r.id = j["id"].dump();
    }
    if (!j.contains("op") || !j["op"].is_string()) throw Invalid{"'op' (a string) is required"};
    r.op = j["op"].get<std::string>();
    const auto op = operations().find(r.op);
    if (op == operations().end()) {
      std::string known;
      for (const auto& [name, keys] : operations()) known += (known.empty() ? "" : ", ") + name;
      const std::string shown = r.op.size() > 40 ? r.op.substr(0, 40) + "..." : r.op;
      r.op.clear();
      throw Invalid{fmt::format("unknown op {} (known: {})",
                                json(shown).dump(-1, ' ', false, json::error_handler_t::replace),
                                known)};
    }
    for (const auto& [key, value] : j.items())
      if (key != "op" && key != "id" && !op->second.count(key))
        throw Invalid{fmt::format("'{}' takes no key {}", r.op, json(key).dump())};
    if (r.op == "state") {
      r.node = j.contains("node") ? integer(j, "node", 0, sim.model().node_count() - 1) : -1;
      r.kind = Request::Kind::state;
      return r;
    }
    r.control = control_of(r.op, j, sim, slides);
    r.kind = Request::Kind::control;
  } catch (const Invalid& e) {
    r.kind = Request::Kind::error;
    r.error = e.message;
  } catch (const json::exception& e) {  // a type the checks above missed
    r.kind = Request::Kind::error;
    r.error = std::string("bad message: ") + e.what();
  }
  return r;
}

std::string scene_message(const LiveSimulation& sim, const DrawnSurface& surface,
                          const std::vector<ObstacleSlide>& slides) {
  const Model& m = sim.model();
  json objects = json::array(), obstacles = json::array(), pressures = json::array(),
       volumes = json::array();
  for (size_t k = 0; k < m.components.size(); ++k)
    objects.push_back({{"name", m.components[k].name},
                       {"kind", kind_name(m.components[k].kind)},
                       {"volumetric", m.components[k].volumetric},
                       {"first_triangle", surface.range[k][0]},
                       {"triangles", surface.range[k][1]}});
  for (size_t k = 0; k < m.obstacles.size(); ++k) {
    const RigidObstacle& o = m.obstacles[k];
    obstacles.push_back({{"name", obstacle_name(m, k)},
                         {"shape", shape_name(o.shape)},
                         {"point", vec(o.point)},
                         {"axis", vec(o.axis)},
                         {"radius", o.radius},
                         {"length", o.length},
                         {"keep_inside", o.keep_inside},
                         {"slide",
                          {{"direction", vec(slides[k].direction)},
                           {"min", slides[k].min},
                           {"max", slides[k].max}}}});
  }
  for (const PressureLoad& p : m.pressures)
    pressures.push_back({{"name", m.components[size_t(p.component)].name}});
  for (const VolumeConstraint& v : m.volumes)
    volumes.push_back({{"name", v.component}, {"rest", v.target_volume}});
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& p : m.rest_position) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return json{{"type", "scene"},
              {"nodes", m.node_count()},
              {"dt", sim.dt()},
              {"size", m.size_scale},
              {"bounds", {vec(lo), vec(hi)}},
              {"objects", objects},
              {"obstacles", obstacles},
              {"pressures", pressures},
              {"volumes", volumes},
              {"monitors", sim.monitor_names()},
              {"colour", {{"name", "displacement"}, {"unit", "m"}}}}
      .dump();
}

std::string state_message(const LiveSimulation& sim, const Snapshot& s, const char* type, int node,
                          const std::string& id) {
  const Model& m = sim.model();
  json obstacles = json::array(), monitors = json::object();
  for (size_t k = 0; k < m.obstacles.size(); ++k)
    obstacles.push_back({{"name", obstacle_name(m, k)},
                         {"translation",
                          {s.obstacle_translation[3 * k], s.obstacle_translation[3 * k + 1],
                           s.obstacle_translation[3 * k + 2]}}});
  for (size_t k = 0; k < s.monitors.size(); ++k) monitors[sim.monitor_names()[k]] = s.monitors[k];
  json j = {{"type", type},
            {"time", s.time},
            {"steps", s.steps},
            {"paused", s.paused},
            {"pace", s.pace == Pace::fast ? "fast" : "realtime"},
            {"real_time_factor", s.real_time_factor},
            {"drag_node", s.drag_node},
            {"error", std::string(s.error.data())},
            {"obstacles", obstacles},
            {"pressures", s.pressure},
            {"target_volumes", s.target_volume},
            {"monitors", monitors}};
  if (node >= 0) {
    const size_t i = size_t(node);
    j["node"] = {{"id", node},
                 {"position", {s.positions[3 * i], s.positions[3 * i + 1], s.positions[3 * i + 2]}},
                 {"rest", vec(m.rest_position[i])},
                 {"displacement", s.displacement[i]}};
  }
  if (!id.empty()) j["id"] = json::parse(id);
  return j.dump();
}

std::string ok_message(const std::string& op, const std::string& id) {
  json j = {{"type", "ok"}, {"op", op}};
  if (!id.empty()) j["id"] = json::parse(id);
  return j.dump();
}

std::string error_message(const std::string& message, const std::string& op,
                          const std::string& id) {
  json j = {{"type", "error"}, {"message", message}};
  if (!op.empty()) j["op"] = op;
  if (!id.empty()) j["id"] = json::parse(id);
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

namespace {
template <class T>
void put(std::string& out, size_t& at, const T* data, size_t count) {
  std::memcpy(out.data() + at, data, count * sizeof(T));
  at += count * sizeof(T);
}
}  // namespace

void encode_mesh(const Model& model, const DrawnSurface& surface, std::string& out) {
  const std::uint32_t n = std::uint32_t(model.node_count());
  const std::uint32_t t = std::uint32_t(surface.triangles.size());
  const std::uint32_t header[3] = {std::uint32_t(BinaryKind::mesh), n, t};
  out.resize(sizeof header + 12 * size_t(t) + 12 * size_t(n));
  size_t at = 0;
  put(out, at, header, 3);
  for (const Triangle& tri : surface.triangles) {
    const std::uint32_t ids[3] = {std::uint32_t(tri[0]), std::uint32_t(tri[1]),
                                  std::uint32_t(tri[2])};
    put(out, at, ids, 3);
  }
  for (const Vec3& p : model.rest_position) {
    const float xyz[3] = {float(p.x()), float(p.y()), float(p.z())};
    put(out, at, xyz, 3);
  }
}

void encode_frame(const Snapshot& s, std::string& out) {
  const std::uint32_t head[2] = {std::uint32_t(BinaryKind::frame), std::uint32_t(s.sequence)};
  const std::uint32_t counts[2] = {std::uint32_t(s.displacement.size()),
                                   std::uint32_t(s.obstacle_translation.size() / 3)};
  out.resize(24 + 4 * (s.positions.size() + s.displacement.size() + s.obstacle_translation.size()));
  size_t at = 0;
  put(out, at, head, 2);
  put(out, at, &s.time, 1);
  put(out, at, counts, 2);
  put(out, at, s.positions.data(), s.positions.size());
  put(out, at, s.displacement.data(), s.displacement.size());
  put(out, at, s.obstacle_translation.data(), s.obstacle_translation.size());
}

}  // namespace phymul::serve
