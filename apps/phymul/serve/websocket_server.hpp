// The network side of `phymul serve`: one port, plain HTTP for the page's fixed files and a
// WebSocket for the stream and the controls, on websocketpp over standalone asio, all on the
// thread that calls run(). This header shows no websocketpp type: its one source file is
// compiled as C++17 (websocketpp 0.8.2's headers are not C++20 for GCC 12).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace phymul::serve {

using ClientId = std::uint64_t;

struct HttpReply {
  int status = 404;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
};

// What a request that asks for a WebSocket carries: the resource ("/ws?token=..."), and the
// Host and Origin headers ("" when absent).
struct UpgradeRequest {
  std::string resource, host, origin;
};

// Called on the network thread.
struct ServerHandlers {
  std::function<std::string(const UpgradeRequest&)> accept;  // "" accepts, else why not (403)
  std::function<void(ClientId)> open, close;
  std::function<void(ClientId, const std::string&)> text;  // a text message (valid UTF-8)
  std::function<void(ClientId, std::size_t)> binary;       // a binary message of this many bytes
  std::function<HttpReply(const std::string& method, const std::string& resource)> http;
  std::function<void()> tick;  // every tick of run()
};

class WebSocketServer {
 public:
  // Messages over max_message_bytes close their connection (1009, "message too big"). Each
  // connection's kernel send buffer is send_buffer_bytes: what a client that stops reading
  // can have waiting for it there, beyond the server's own queue.
  WebSocketServer(ServerHandlers handlers, std::size_t max_message_bytes,
                  std::size_t send_buffer_bytes);
  ~WebSocketServer();
  WebSocketServer(const WebSocketServer&) = delete;
  WebSocketServer& operator=(const WebSocketServer&) = delete;

  // Binds host:port (port 0: any free one) and returns the port bound; std::runtime_error
  // saying why it could not.
  int listen(const std::string& host, int port);
  // Serves until stop() or SIGINT / SIGTERM, calling handlers.tick every tick; then closes
  // every connection (1001, going away) and returns.
  void run(std::chrono::milliseconds tick);
  void stop();  // from a handler

  // False when the client is gone. Each copies the payload into the connection's queue.
  bool send_text(ClientId client, const std::string& text);
  bool send_binary(ClientId client, const void* data, std::size_t bytes);
  // Bytes queued for the client and not yet written to its socket (0 when it is gone).
  std::size_t buffered(ClientId client) const;
  void close(ClientId client, std::uint16_t code, const std::string& reason);
  bool signalled() const;  // run() ended on SIGINT or SIGTERM

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace phymul::serve
