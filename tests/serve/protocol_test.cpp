// phymul serve's protocol, with a real server process and real WebSocket clients: what it
// streams, the controls, and every kind of bad message (an error reply each, the simulation
// stepping on).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "serve_client.hpp"

namespace phymul::testing {
namespace {

const std::string kBlock = "tests/data/serve/block.yaml";

std::vector<float> floats(const std::string& bytes, size_t offset, size_t count) {
  std::vector<float> v(count);
  std::memcpy(v.data(), bytes.data() + offset, 4 * count);
  return v;
}

std::uint32_t word(const std::string& bytes, size_t offset) {
  std::uint32_t w = 0;
  std::memcpy(&w, bytes.data() + offset, 4);
  return w;
}

bool is_type(const json& m, const char* type) {
  return m.is_object() && m.value("type", "") == type;
}

double norm(const json& a, const json& b) {
  double s = 0;
  for (int k = 0; k < 3; ++k) s += std::pow(a[k].get<double>() - b[k].get<double>(), 2);
  return std::sqrt(s);
}

// A served block and one client connected to it.
struct Served {
  ServerProcess server{{scene_path(kBlock), "--port", "0", "--threads", "1"}};
  Client client;
  json scene;
  Served() {
    const std::string why = client.connect(server.port());
    if (!why.empty()) throw std::runtime_error("cannot connect: " + why);
    scene = client.wait_for([](const json& m) { return is_type(m, "scene"); });
  }
};

TEST(ServeProtocol, SendsTheSceneThenTheTrianglesThenFramesOfEveryNode) {
  Served s;
  ASSERT_TRUE(is_type(s.scene, "scene"));
  const size_t nodes = s.scene["nodes"];
  EXPECT_EQ(nodes, 7u * 7u * 4u);  // the 6 x 6 x 3 box
  EXPECT_EQ(s.scene["obstacles"][0]["name"], "probe");
  EXPECT_EQ(s.scene["monitors"][0], "probe force (N)");
  while (s.client.frames() < 10) std::this_thread::sleep_for(10ms);
  const std::string mesh = s.client.first_binary();
  ASSERT_GE(mesh.size(), 12u);
  EXPECT_EQ(word(mesh, 0), 1u);
  EXPECT_EQ(word(mesh, 4), nodes);
  const size_t triangles = word(mesh, 8);
  EXPECT_EQ(triangles, 2u * 2 * (6 * 6 + 6 * 3 + 6 * 3));  // the box's faces, quads split in two
  EXPECT_EQ(mesh.size(), 12 + 12 * triangles + 12 * nodes);
  for (size_t k = 0; k < 3 * triangles; ++k) ASSERT_LT(word(mesh, 12 + 4 * k), nodes);
  const std::string frame = s.client.last_frame();
  EXPECT_EQ(word(frame, 0), 2u);
  EXPECT_EQ(word(frame, 16), nodes);
  EXPECT_EQ(word(frame, 20), 1u);  // one obstacle
  ASSERT_EQ(frame.size(), 24 + 16 * nodes + 12);
  // At rest (no load yet): the frame's positions are the rest positions, within float's.
  const std::vector<float> rest = floats(mesh, 12 + 12 * triangles, 3 * nodes);
  const std::vector<float> now = floats(frame, 24, 3 * nodes);
  for (size_t k = 0; k < 3 * nodes; ++k) ASSERT_NEAR(now[k], rest[k], 1e-6);
  double time = 0;
  std::memcpy(&time, frame.data() + 8, 8);
  EXPECT_GT(time, 0.0);
}

TEST(ServeProtocol, EveryBadMessageGetsAnErrorAndTheSimulationStepsOn) {
  Served s;
  const double before = s.client.state()["time"];
  std::mt19937 random(7);
  std::string garbage(3000, '\0');
  for (char& c : garbage) c = char(random());
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"{\"op\": \"play\"", "not JSON"},
      {"[1, 2, 3]", "must be a JSON object"},
      {"\"play\"", "must be a JSON object"},
      {"{}", "'op' (a string) is required"},
      {"{\"op\": 3}", "'op' (a string) is required"},
      {"{\"op\": \"fly\"}", "unknown op \"fly\""},
      {"{\"op\": \"play\", \"speed\": 2}", "'play' takes no key \"speed\""},
      {"{\"op\": \"step\", \"n\": -1}", "'n' must be an integer in [1, 10000]"},
      {"{\"op\": \"step\", \"n\": 1.5}", "'n' must be an integer"},
      {"{\"op\": \"drag\", \"node\": 100000, \"target\": [0, 0, 0]}", "'node' must be an integer"},
      {"{\"op\": \"drag\", \"node\": 147, \"target\": [0, 0, 0]}", "held by a constraint"},
      {"{\"op\": \"drag\", \"node\": 1, \"target\": [0, 0]}", "array of 3 numbers"},
      {"{\"op\": \"drag\", \"node\": 1, \"target\": [1e300, 0, 0]}", "at most"},
      {"{\"op\": \"move_obstacle\", \"obstacle\": \"knife\", \"offset\": 0}",
       "no obstacle named 'knife'"},
      {"{\"op\": \"move_obstacle\", \"obstacle\": 0, \"offset\": 5}", "'offset' must be in"},
      {"{\"op\": \"set_pressure\", \"load\": 3, \"value\": 1}", "no pressure load 3"},
      {"{\"op\": \"set_target_volume\", \"object\": 0, \"value\": -1}", "'value' must be in (0"},
      {"{\"op\": \"pace\", \"value\": \"slow\"}", "\"realtime\" or \"fast\""},
      {"{\"op\": \"state\", \"id\": [1]}", "'id' must be an integer or a string"},
      {"{\"op\": \"state\", \"file\": \"/etc/passwd\"}", "'state' takes no key \"file\""},
      {"{\"op\": \"play\", \"pad\": \"" + std::string(5000, 'x') + "\"}", "message too large"},
      {std::string(200, '['), "not JSON"},
  };
  for (const auto& [message, expected] : bad) {
    s.client.send_text(message);
    const json reply = s.client.wait_for([](const json& m) { return is_type(m, "error"); });
    ASSERT_TRUE(is_type(reply, "error")) << "no error reply to " << message.substr(0, 80);
    EXPECT_NE(reply["message"].get<std::string>().find(expected), std::string::npos)
        << message.substr(0, 80) << " -> " << reply["message"];
  }
  s.client.send_binary(garbage);
  const json reply = s.client.wait_for([](const json& m) { return is_type(m, "error"); });
  EXPECT_NE(reply.value("message", "").find("binary messages are not accepted"), std::string::npos);
  // Still connected, still stepping: simulated time went on.
  std::this_thread::sleep_for(300ms);
  const json after = s.client.state();
  ASSERT_TRUE(is_type(after, "state"));
  EXPECT_GT(after["time"].get<double>(), before + 0.1);
  EXPECT_EQ(after["error"], "");
  EXPECT_EQ(s.client.close_code(), 0);
}

TEST(ServeProtocol, AMessageOverAMebibyteClosesThatConnectionOnly) {
  Served s;
  Client other;
  ASSERT_EQ(other.connect(s.server.port()), "");
  s.client.send_text(std::string(2 << 20, ' '));
  for (int k = 0; k < 500 && s.client.close_code() == 0; ++k) std::this_thread::sleep_for(10ms);
  EXPECT_EQ(s.client.close_code(), 1009);  // message too big
  const double t0 = other.state()["time"];
  std::this_thread::sleep_for(200ms);
  EXPECT_GT(other.state()["time"].get<double>(), t0);
}

TEST(ServeProtocol, AFloodIsRateLimitedWithAnErrorASecondAndServedAgainAfterwards) {
  Served s;
  for (int k = 0; k < 600; ++k) s.client.send_text("{\"op\": \"state\"}");
  const json refused = s.client.wait_for([](const json& m) { return is_type(m, "error"); }, 10s);
  EXPECT_NE(refused.value("message", "").find("rate limit"), std::string::npos);
  // At most one rate-limit error a second, whatever the flood.
  int errors = 1;
  while (!s.client.wait_for([](const json& m) { return is_type(m, "error"); }, 2500ms).is_null())
    ++errors;
  EXPECT_LE(errors, 4);
  EXPECT_TRUE(is_type(s.client.state(), "state"));
}

TEST(ServeProtocol, PauseStopsTimeStepAdvancesByStepsPlayResumes) {
  Served s;
  EXPECT_TRUE(is_type(s.client.request({{"op", "pause"}}), "ok"));
  json paused;
  for (int k = 0; k < 100; ++k) {
    paused = s.client.state();
    if (paused["paused"] == true) break;
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_EQ(paused["paused"], true);
  std::this_thread::sleep_for(300ms);
  const json still = s.client.state();
  EXPECT_EQ(still["time"], paused["time"]);
  EXPECT_EQ(still["steps"], paused["steps"]);
  EXPECT_EQ(still["real_time_factor"], 0.0);

  s.client.request({{"op", "step"}, {"n", 3}});
  json stepped;
  for (int k = 0; k < 100; ++k) {
    stepped = s.client.state();
    if (stepped["steps"] == paused["steps"].get<long>() + 3) break;
    std::this_thread::sleep_for(10ms);
  }
  EXPECT_EQ(stepped["steps"], paused["steps"].get<long>() + 3);
  EXPECT_NEAR(stepped["time"].get<double>() - paused["time"].get<double>(),
              3 * s.scene["dt"].get<double>(), 1e-12);
  EXPECT_EQ(stepped["paused"], true);

  s.client.request({{"op", "play"}});
  std::this_thread::sleep_for(500ms);
  const json playing = s.client.state();
  EXPECT_EQ(playing["paused"], false);
  // Real time: half a second later, about half a second more (a loaded machine may lag).
  EXPECT_GT(playing["time"].get<double>() - stepped["time"].get<double>(), 0.2);
  EXPECT_LT(playing["time"].get<double>() - stepped["time"].get<double>(), 0.7);
}

// Nodes of the 7 x 7 x 4 grid, i + 7 j + 49 k (k = 0 at the bottom, z = -1 cm): the bottom
// face's centre, on the probe's tip, and a bottom node off the probe.
constexpr int kBottomCentre = 3 + 7 * 3;
constexpr int kBottomAside = 1 + 7 * 1;

TEST(ServeProtocol, DraggingANodePullsItTowardsThePointerAndReleasingLetsItBack) {
  Served s;
  const int node = kBottomAside;
  const json rest = s.client.state(node)["node"]["rest"];
  ASSERT_NEAR(rest[2].get<double>(), -0.01, 1e-12);
  ASSERT_NEAR(rest[0].get<double>(), -0.04 / 3, 1e-12);
  json target = rest;
  target[2] = -0.02;  // 1 cm down
  EXPECT_TRUE(
      is_type(s.client.request({{"op", "drag"}, {"node", node}, {"target", target}}), "ok"));
  std::this_thread::sleep_for(1500ms);
  const json pulled = s.client.state(node);
  EXPECT_EQ(pulled["drag_node"], node);
  const double down = rest[2].get<double>() - pulled["node"]["position"][2].get<double>();
  EXPECT_GT(down, 1e-3) << "moved " << down << " m towards a target 1 cm away";
  EXPECT_LT(down, 0.01);
  EXPECT_LT(norm(pulled["node"]["position"], target), 0.01);

  s.client.request({{"op", "release"}});
  std::this_thread::sleep_for(1500ms);
  const json back = s.client.state(node);
  EXPECT_EQ(back["drag_node"], -1);
  EXPECT_LT(norm(back["node"]["position"], rest), 0.2 * down);
}

TEST(ServeProtocol, TheProbeSliderMovesTheProbeWhichPushesTheBlock) {
  Served s;
  const int node = kBottomCentre;
  EXPECT_TRUE(is_type(
      s.client.request({{"op", "move_obstacle"}, {"obstacle", "probe"}, {"offset", 0.008}}), "ok"));
  std::this_thread::sleep_for(1500ms);  // 8 mm at 5 cm/s: 0.16 s, then settling
  const json pushed = s.client.state(node);
  EXPECT_NEAR(pushed["obstacles"][0]["translation"][2].get<double>(), 0.008, 1e-6);
  // The tip touched the bottom face's centre at rest: that node rides on it, 8 mm up (less a
  // little where the contact's projection and the block's volume share the push).
  const double up =
      pushed["node"]["position"][2].get<double>() - pushed["node"]["rest"][2].get<double>();
  EXPECT_GT(up, 7e-3);
  EXPECT_LT(up, 8.2e-3);
  EXPECT_GT(pushed["monitors"]["probe force (N)"].get<double>(), 0.0);
}

TEST(ServeProtocol, PressureAndTargetVolumeFollowTheirControls) {
  Served s;
  s.client.request({{"op", "set_pressure"}, {"load", "block"}, {"value", 150.0}});
  const double rest = s.scene["volumes"][0]["rest"];
  s.client.request({{"op", "set_target_volume"}, {"object", "block"}, {"value", 1.1 * rest}});
  std::this_thread::sleep_for(800ms);  // ramps: 0.1 s, and 10 % at 200 % a second
  const json state = s.client.state();
  EXPECT_DOUBLE_EQ(state["pressures"][0].get<double>(), 150.0);
  EXPECT_NEAR(state["target_volumes"][0].get<double>(), 1.1 * rest, 1e-12);
  EXPECT_NEAR(state["monitors"]["block volume (mL)"].get<double>(), 1.1 * rest * 1e6,
              1e-3 * rest * 1e6);
  EXPECT_NEAR(state["monitors"]["block pressure (kPa)"].get<double>(), 0.15, 1e-12);
}

TEST(ServeProtocol, AForceOnANodeMovesItAlongTheForceUntilRemoved) {
  Served s;
  const int node = kBottomAside;
  EXPECT_TRUE(is_type(
      s.client.request({{"op", "set_force"}, {"node", node}, {"force", {0.0, 0.0, -0.02}}}), "ok"));
  std::this_thread::sleep_for(1500ms);
  const json pushed = s.client.state(node)["node"];
  const double down = pushed["rest"][2].get<double>() - pushed["position"][2].get<double>();
  EXPECT_GT(down, 5e-4);
  s.client.request({{"op", "set_force"}, {"node", node}, {"force", {0.0, 0.0, 0.0}}});
  std::this_thread::sleep_for(1500ms);
  const json back = s.client.state(node)["node"];
  EXPECT_LT(norm(back["position"], back["rest"]), 0.2 * down);
}

TEST(ServeProtocol, ResetPutsTheRunBackAtTimeZero) {
  Served s;
  std::this_thread::sleep_for(300ms);
  s.client.request({{"op", "move_obstacle"}, {"obstacle", 0}, {"offset", 0.005}});
  s.client.request({{"op", "reset"}});
  s.client.request({{"op", "pause"}});
  std::this_thread::sleep_for(100ms);
  const json state = s.client.state();
  EXPECT_LT(state["time"].get<double>(), 0.1);
  EXPECT_EQ(state["obstacles"][0]["translation"][2], 0.0);
}

}  // namespace
}  // namespace phymul::testing
