// The live view's tests: a `phymul serve` process, and a WebSocket client (websocketpp, as
// the server; built as C++17 for the same reason) that keeps what the server sends.
#pragma once

#include <signal.h>
#include <sys/types.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>
#include <websocketpp/client.hpp>
#include <websocketpp/config/asio_no_tls_client.hpp>

namespace phymul::testing {

using nlohmann::json;
using namespace std::chrono_literals;

// `phymul serve ARGS --port 0`, its port read from what it prints.
class ServerProcess {
 public:
  explicit ServerProcess(const std::vector<std::string>& args);
  ~ServerProcess();
  int port() const { return port_; }
  pid_t pid() const { return pid_; }
  const std::string& banner() const { return banner_; }
  std::string output() const;  // what it printed so far (stdout and stderr)
  // Sends `signal` and waits up to `patience` for the exit: its status (-1: still running,
  // then killed).
  int stop(int signal, std::chrono::milliseconds patience = 10s);
  long rss_kib() const;  // resident memory now, /proc/PID/status
  // CPU time (s, user and system) of its thread named `name` so far; -1 when there is none.
  double thread_cpu_seconds(const std::string& name) const;

 private:
  pid_t pid_ = -1;
  int port_ = 0;
  std::string banner_;
  std::filesystem::path log_;
};

// Runs `phymul ARGS` to its end: exit status and stdout + stderr.
struct Finished {
  int exit_code = -1;
  std::string output;
};
Finished run_cli(const std::vector<std::string>& args);

std::string scene_path(const std::string& relative);  // under the source tree

class Client {
 public:
  using Endpoint = websocketpp::client<websocketpp::config::asio_client>;
  Client();
  ~Client();
  // Connects to ws://127.0.0.1:PORT + resource with these extra headers; "" when open, else
  // why not (the HTTP status or the error).
  std::string connect(int port, const std::string& resource = "/ws",
                      const std::vector<std::pair<std::string, std::string>>& headers = {});
  // A slow client: a small socket receive buffer (before connect), and a stall of its thread
  // at the next frame (it reads nothing meanwhile).
  void set_receive_buffer(int bytes) { receive_buffer_ = bytes; }
  void stall_at_next_frame(std::chrono::milliseconds stall) { stall_ = stall; }
  void send_text(const std::string& text);
  void send_binary(const std::string& bytes);
  // The first text message since the last call that satisfies `pick` (messages before it are
  // dropped), or a null json after `timeout`.
  json wait_for(const std::function<bool(const json&)>& pick,
                std::chrono::milliseconds timeout = 5s);
  json request(json message,
               std::chrono::milliseconds timeout = 5s);  // adds an id, waits its reply
  json state(int node = -1);
  long frames() const;
  std::string first_binary() const;  // the first binary message (the triangles)
  std::string last_frame() const;
  int close_code() const;  // 0 while open
  void close();

 private:
  Endpoint endpoint_;
  websocketpp::connection_hdl handle_;
  std::thread thread_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<json> texts_;
  std::string first_binary_, last_frame_;
  long frames_ = 0;
  int close_code_ = 0;
  bool open_ = false, failed_ = false;
  std::string fail_reason_;
  int next_id_ = 1;
  int receive_buffer_ = 0;
  std::chrono::milliseconds stall_{0};
};

}  // namespace phymul::testing
