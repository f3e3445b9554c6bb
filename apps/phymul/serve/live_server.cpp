#include "live_server.hpp"

#include <fmt/format.h>

namespace phymul::serve {
namespace {

using Clock = std::chrono::steady_clock;
constexpr size_t kMaxClients = 64;
constexpr size_t kMaxMessageBytes = 1 << 20;  // a larger message closes its connection (1009)
constexpr double kMessagesPerSecond = 100.0, kBurst = 200.0;
constexpr int kStatusEvery = 6;            // ticks (of 1/60 s): status ten times a second
constexpr size_t kStatusSlack = 64 << 10;  // bytes a slow client may have queued beyond a frame

// The value of `key` in a URL's query ("" when absent).
std::string query_value(const std::string& resource, const std::string& key) {
  const size_t q = resource.find('?');
  if (q == std::string::npos) return "";
  size_t at = q + 1;
  while (at <= resource.size()) {
    const size_t end = std::min(resource.find('&', at), resource.size());
    const std::string pair = resource.substr(at, end - at);
    if (pair.rfind(key + "=", 0) == 0) return pair.substr(key.size() + 1);
    at = end + 1;
  }
  return "";
}

// A few frames' worth (at least 64 KiB): a client that stops reading has at most that much
// waiting in the kernel, then gets the latest frame when it reads again.
size_t send_buffer(const LiveSimulation& sim) {
  const size_t frame =
      24 + 16 * size_t(sim.model().node_count()) + 12 * sim.model().obstacles.size();
  return std::max<size_t>(4 * frame, 64 << 10);
}

std::string path_of(const std::string& resource) { return resource.substr(0, resource.find('?')); }

// Compares in a time that does not depend on where the strings first differ.
bool same_secret(const std::string& given, const std::string& secret) {
  if (given.size() != secret.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < given.size(); ++i) diff |= (unsigned char)(given[i] ^ secret[i]);
  return diff == 0;
}

// The host name of a Host header ("127.0.0.1:8080" -> "127.0.0.1", "[::1]:80" -> "[::1]").
std::string host_name(const std::string& header) {
  if (!header.empty() && header[0] == '[') return header.substr(0, header.find(']') + 1);
  return header.substr(0, header.find(':'));
}

}  // namespace

LiveServer::LiveServer(LiveSimulation& sim, ServerOptions options, WebAssets assets)
    : sim_(sim),
      options_(std::move(options)),
      assets_(std::move(assets)),
      surface_(drawn_surface(sim.model())),
      slides_(obstacle_slides(sim.model())),
      snapshot_(sim.make_snapshot()),
      ws_(ServerHandlers{[this](const UpgradeRequest& r) { return accept(r); },
                         [this](ClientId c) { open(c); },
                         [this](ClientId c) {
                           clients_.erase(c);
                           sim_.set_watched(!clients_.empty());
                         },
                         [this](ClientId c, const std::string& m) { text(c, m); },
                         [this](ClientId c, std::size_t) { binary(c); },
                         [this](const std::string& method, const std::string& resource) {
                           return http(method, resource);
                         },
                         [this] { tick(); }},
          kMaxMessageBytes, send_buffer(sim)) {
  scene_json_ = scene_message(sim_, surface_, slides_);
  encode_mesh(sim_.model(), surface_, mesh_bytes_);
  if (sim_.latest(snapshot_)) encode_frame(snapshot_, frame_bytes_);
}

int LiveServer::listen() { return ws_.listen(options_.host, options_.port); }

void LiveServer::run() { ws_.run(std::chrono::milliseconds(16)); }

// A WebSocket only at /ws, from a page of this server (no other site's page may drive it), and
// with the token when there is one; without one, only under a loopback name (a page that
// rebinds its own name to 127.0.0.1 is refused).
std::string LiveServer::accept(const UpgradeRequest& r) const {
  if (path_of(r.resource) != "/ws") return "the WebSocket is at /ws";
  if (clients_.size() >= kMaxClients) return fmt::format("at most {} clients", kMaxClients);
  if (!r.origin.empty() && r.origin != "http://" + r.host)
    return "a page of another site may not connect";
  if (!options_.token.empty()) {
    if (!same_secret(query_value(r.resource, "token"), options_.token))
      return "wrong or missing token (open the page as http://HOST:PORT/?token=TOKEN)";
    return "";
  }
  const std::string name = host_name(r.host);
  if (name != "127.0.0.1" && name != "localhost" && name != "[::1]")
    return "without --token the server answers only as 127.0.0.1 or localhost";
  return "";
}

HttpReply LiveServer::http(const std::string& method, const std::string& resource) const {
  if (method != "GET") return {405, "text/plain; charset=utf-8", "only GET\n"};
  const auto it = assets_.files.find(path_of(resource));
  if (it == assets_.files.end()) return {404, "text/plain; charset=utf-8", "not found\n"};
  return {200, it->second.content_type, it->second.body};
}

void LiveServer::open(ClientId c) {
  clients_[c] = Client{kBurst, Clock::now(), {}, 0};
  sim_.set_watched(true);
  ws_.send_text(c, scene_json_);
  ws_.send_binary(c, mesh_bytes_.data(), mesh_bytes_.size());
}

bool LiveServer::allow(Client& c) {
  const Clock::time_point now = Clock::now();
  c.tokens =
      std::min(kBurst, c.tokens + kMessagesPerSecond *
                                      std::chrono::duration<double>(now - c.refilled).count());
  c.refilled = now;
  if (c.tokens < 1.0) return false;
  c.tokens -= 1.0;
  return true;
}

void LiveServer::text(ClientId id, const std::string& message) {
  Client& c = clients_[id];
  if (!allow(c)) {
    const Clock::time_point now = Clock::now();
    if (now - c.last_refusal >= std::chrono::seconds(1)) {  // one error a second, not one each
      ws_.send_text(id, error_message(fmt::format("rate limit: at most {:g} messages a second; "
                                                  "messages dropped",
                                                  kMessagesPerSecond),
                                      "", ""));
      c.last_refusal = now;
    }
    return;
  }
  const Request r = parse_request(message, sim_, slides_);
  switch (r.kind) {
    case Request::Kind::error:
      ws_.send_text(id, error_message(r.error, r.op, r.id));
      break;
    case Request::Kind::state:
      if (sim_.latest(snapshot_)) encode_frame(snapshot_, frame_bytes_);
      ws_.send_text(id, state_message(sim_, snapshot_, "state", r.node, r.id));
      break;
    case Request::Kind::control:
      if (sim_.submit(r.control))
        ws_.send_text(id, ok_message(r.op, r.id));
      else
        ws_.send_text(id, error_message("busy: too many controls waiting", r.op, r.id));
      break;
  }
}

void LiveServer::binary(ClientId id) {
  Client& c = clients_[id];
  if (!allow(c)) return;
  ws_.send_text(id, error_message("binary messages are not accepted: send JSON text, "
                                  "{\"op\": ...}",
                                  "", ""));
}

// 60 times a second: the latest frame to every client whose last one has left, status ten
// times a second.
void LiveServer::tick() {
  if (sim_.latest(snapshot_)) encode_frame(snapshot_, frame_bytes_);
  const bool status = ++ticks_ % kStatusEvery == 0;
  std::string status_json;
  if (status) status_json = state_message(sim_, snapshot_, "status", -1, "");
  for (auto& [id, c] : clients_) {
    const size_t queued = ws_.buffered(id);
    if (c.sent < snapshot_.sequence && queued < frame_bytes_.size()) {
      ws_.send_binary(id, frame_bytes_.data(), frame_bytes_.size());
      c.sent = snapshot_.sequence;
    }
    if (status && queued < frame_bytes_.size() + kStatusSlack) ws_.send_text(id, status_json);
  }
}

}  // namespace phymul::serve
