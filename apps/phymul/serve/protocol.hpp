// The live view's messages (docs/live-view.md has the protocol). Clients send JSON text, one
// operation each, checked here against the schema and the model; the server sends JSON text
// (the scene, status, replies, errors) and binary frames (the triangles once, then positions
// and the colour scalar as little-endian float32).
#pragma once

#include <string>
#include <vector>

#include "live_simulation.hpp"

namespace phymul::serve {

constexpr size_t kMaxRequestBytes = 4096;  // a longer message is refused with an error reply

// A client's message, checked.
struct Request {
  enum class Kind { control, state, error };
  Kind kind = Kind::error;
  std::string op;  // as sent ("" when there was none)
  Control control;
  int node = -1;      // state: the node to report, -1: none
  std::string id;     // the client's "id", as JSON text, echoed in the reply ("" when none)
  std::string error;  // Kind::error: what was wrong
};

// The direction a slider moves an obstacle along, and how far (m): the direction of its
// scene motion where it has one, else its axis.
struct ObstacleSlide {
  Vec3 direction = Vec3::UnitZ();
  double min = 0.0, max = 0.0;
};

// Surface triangles to draw (global node ids): each component's boundary, or its cells when
// the surface is open; and where each component's run of them starts.
struct DrawnSurface {
  std::vector<Triangle> triangles;
  std::vector<std::array<int, 2>> range;  // per component: first triangle, count
};

DrawnSurface drawn_surface(const Model& model);
std::vector<ObstacleSlide> obstacle_slides(const Model& model);

Request parse_request(const std::string& text, const LiveSimulation& sim,
                      const std::vector<ObstacleSlide>& slides);

// JSON texts.
std::string scene_message(const LiveSimulation& sim, const DrawnSurface& surface,
                          const std::vector<ObstacleSlide>& slides);
// type "status" (broadcast) or "state" (a reply, with `node` when >= 0).
std::string state_message(const LiveSimulation& sim, const Snapshot& s, const char* type, int node,
                          const std::string& id);
std::string ok_message(const std::string& op, const std::string& id);
std::string error_message(const std::string& message, const std::string& op, const std::string& id);

// Binary messages; `out` is resized, so a reused buffer stops allocating after the first.
enum class BinaryKind : std::uint32_t { mesh = 1, frame = 2 };
void encode_mesh(const Model& model, const DrawnSurface& surface, std::string& out);
void encode_frame(const Snapshot& s, std::string& out);

}  // namespace phymul::serve
