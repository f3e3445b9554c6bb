// `phymul serve`'s server: the page over HTTP, and over a WebSocket the scene, the frames and
// the controls of a LiveSimulation, to any number of clients. Each client gets the latest
// frame when its connection has sent the previous one: a slow client gets fewer frames, and
// nothing a client does makes the simulation wait.
#pragma once

#include <map>
#include <memory>
#include <string>

#include "live_simulation.hpp"
#include "protocol.hpp"
#include "web_assets.hpp"
#include "websocket_server.hpp"

namespace phymul::serve {

struct ServerOptions {
  std::string host = "127.0.0.1";
  int port = 8080;
  std::string token;  // required of every WebSocket client when not empty
};

class LiveServer {
 public:
  LiveServer(LiveSimulation& sim, ServerOptions options, WebAssets assets);
  int listen();  // the port bound
  void run();    // until Ctrl-C (SIGINT) or SIGTERM
  bool signalled() const { return ws_.signalled(); }

 private:
  // Per client: a token bucket of messages, and what it has been sent.
  struct Client {
    double tokens = 0.0;
    std::chrono::steady_clock::time_point refilled, last_refusal;
    long sent = 0;  // the last frame sent (Snapshot::sequence)
  };
  std::string accept(const UpgradeRequest& r) const;
  HttpReply http(const std::string& method, const std::string& resource) const;
  void open(ClientId c);
  void binary(ClientId c);
  void text(ClientId c, const std::string& message);
  void tick();
  bool allow(Client& c);

  LiveSimulation& sim_;
  ServerOptions options_;
  WebAssets assets_;
  DrawnSurface surface_;
  std::vector<ObstacleSlide> slides_;
  std::string scene_json_, mesh_bytes_, frame_bytes_;
  Snapshot snapshot_;
  int ticks_ = 0;
  std::map<ClientId, Client> clients_;
  WebSocketServer ws_;
};

}  // namespace phymul::serve
