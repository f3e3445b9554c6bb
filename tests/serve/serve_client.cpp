#include "serve_client.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace phymul::testing {
namespace {

std::string environment(const char* name) {
  const char* v = std::getenv(name);
  if (!v || !*v) throw std::runtime_error(std::string(name) + " is not set: run through ctest");
  return v;
}

std::vector<char*> argv_of(std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return argv;
}

}  // namespace

std::string scene_path(const std::string& relative) {
  return environment("PHYMUL_SOURCE_DIR") + "/" + relative;
}

ServerProcess::ServerProcess(const std::vector<std::string>& given) {
  std::vector<std::string> args = {environment("PHYMUL_CLI"), "serve"};
  args.insert(args.end(), given.begin(), given.end());
  static int count = 0;
  log_ = std::filesystem::temp_directory_path() /
         ("phymul_serve_" + std::to_string(getpid()) + "_" + std::to_string(count++) + ".log");
  pid_ = fork();
  if (pid_ == 0) {  // the server's output into the log, which the banner is read from
    const int fd = open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, STDOUT_FILENO);
    dup2(fd, STDERR_FILENO);
    close(fd);
    std::vector<char*> argv = argv_of(args);
    execv(argv[0], argv.data());
    _exit(127);
  }
  // The banner names the port: "... open http://127.0.0.1:PORT/ ...".
  const auto end = std::chrono::steady_clock::now() + 120s;
  std::smatch m;
  while (std::chrono::steady_clock::now() < end) {
    banner_ = output();
    if (std::regex_search(banner_, m, std::regex(R"(http://[^/]+:(\d+)/)"))) {
      port_ = std::stoi(m[1]);
      return;
    }
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      break;
    }
    std::this_thread::sleep_for(20ms);
  }
  stop(SIGKILL, 2s);
  throw std::runtime_error("phymul serve did not say its port: '" + banner_ + "'");
}

std::string ServerProcess::output() const {
  std::ifstream in(log_);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

ServerProcess::~ServerProcess() {
  if (pid_ > 0) stop(SIGKILL, 5s);
  std::error_code ec;
  std::filesystem::remove(log_, ec);
}

int ServerProcess::stop(int signal, std::chrono::milliseconds patience) {
  if (pid_ <= 0) return -1;
  kill(pid_, signal);
  const auto end = std::chrono::steady_clock::now() + patience;
  int status = 0;
  while (std::chrono::steady_clock::now() < end) {
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    std::this_thread::sleep_for(10ms);
  }
  kill(pid_, SIGKILL);
  waitpid(pid_, &status, 0);
  pid_ = -1;
  return -1;
}

long ServerProcess::rss_kib() const {
  std::ifstream in("/proc/" + std::to_string(pid_) + "/status");
  std::string key;
  long value = 0;
  while (in >> key) {
    if (key == "VmRSS:") {
      in >> value;
      return value;
    }
    std::getline(in, key);
  }
  return -1;
}

double ServerProcess::thread_cpu_seconds(const std::string& name) const {
  const std::filesystem::path tasks = "/proc/" + std::to_string(pid_) + "/task";
  std::error_code ec;
  for (const auto& task : std::filesystem::directory_iterator(tasks, ec)) {
    std::ifstream comm(task.path() / "comm");
    std::string got;
    std::getline(comm, got);
    if (got != name) continue;
    std::ifstream stat(task.path() / "stat");
    std::string text;
    std::getline(stat, text);
    // Fields after the command's closing parenthesis: state is 3rd, utime 14th, stime 15th.
    std::istringstream rest(text.substr(text.rfind(')') + 2));
    std::string field;
    double ticks = 0;
    for (int k = 3; k <= 15 && rest >> field; ++k)
      if (k >= 14) ticks += std::stod(field);
    return ticks / double(sysconf(_SC_CLK_TCK));
  }
  return -1;
}

Finished run_cli(const std::vector<std::string>& given) {
  std::string command = environment("PHYMUL_CLI");
  for (const std::string& a : given) command += " '" + a + "'";
  Finished f;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return f;
  std::array<char, 4096> buffer{};
  while (size_t n = fread(buffer.data(), 1, buffer.size(), pipe)) f.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  f.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return f;
}

Client::Client() {
  endpoint_.clear_access_channels(websocketpp::log::alevel::all);
  endpoint_.clear_error_channels(websocketpp::log::elevel::all);
  endpoint_.init_asio();
  endpoint_.set_max_message_size(256 << 20);
  endpoint_.set_socket_init_handler([this](websocketpp::connection_hdl, asio::ip::tcp::socket& s) {
    asio::error_code ec;  // opened here so that the buffer is set before the handshake's window
    if (receive_buffer_ <= 0) return;
    s.open(asio::ip::tcp::v4(), ec);
    s.set_option(asio::socket_base::receive_buffer_size(receive_buffer_), ec);
  });
  endpoint_.set_open_handler([this](websocketpp::connection_hdl) {
    std::lock_guard lock(mutex_);
    open_ = true;
    changed_.notify_all();
  });
  endpoint_.set_fail_handler([this](websocketpp::connection_hdl h) {
    std::lock_guard lock(mutex_);
    failed_ = true;
    auto c = endpoint_.get_con_from_hdl(h);
    fail_reason_ = "HTTP " + std::to_string(c->get_response_code()) + ": " + c->get_ec().message();
    changed_.notify_all();
  });
  endpoint_.set_close_handler([this](websocketpp::connection_hdl h) {
    std::lock_guard lock(mutex_);
    close_code_ = endpoint_.get_con_from_hdl(h)->get_remote_close_code();
    if (close_code_ == 0) close_code_ = 1006;
    changed_.notify_all();
  });
  endpoint_.set_message_handler([this](websocketpp::connection_hdl, Endpoint::message_ptr m) {
    std::lock_guard lock(mutex_);
    if (m->get_opcode() == websocketpp::frame::opcode::text) {
      texts_.push_back(json::parse(m->get_payload(), nullptr, false));
      if (texts_.size() > 2000) texts_.pop_front();
    } else if (first_binary_.empty()) {
      first_binary_ = m->get_payload();
    } else {
      last_frame_ = m->get_payload();
      ++frames_;
    }
    changed_.notify_all();
    if (stall_.count() > 0 && frames_ > 0) {  // the thread that reads the socket stops here
      const auto stall = stall_;
      stall_ = std::chrono::milliseconds(0);
      mutex_.unlock();
      std::this_thread::sleep_for(stall);
      mutex_.lock();
    }
  });
}

Client::~Client() { close(); }

std::string Client::connect(int port, const std::string& resource,
                            const std::vector<std::pair<std::string, std::string>>& headers) {
  websocketpp::lib::error_code ec;
  auto c = endpoint_.get_connection("ws://127.0.0.1:" + std::to_string(port) + resource, ec);
  if (ec) return ec.message();
  for (const auto& [k, v] : headers) c->replace_header(k, v);
  handle_ = c->get_handle();
  endpoint_.connect(c);
  thread_ = std::thread([this] { endpoint_.run(); });
  std::unique_lock lock(mutex_);
  if (!changed_.wait_for(lock, 10s, [this] { return open_ || failed_ || close_code_; }))
    return "timed out";
  return open_ ? "" : (failed_ ? fail_reason_ : "closed");
}

void Client::send_text(const std::string& text) {
  websocketpp::lib::error_code ec;
  endpoint_.send(handle_, text, websocketpp::frame::opcode::text, ec);
}

void Client::send_binary(const std::string& bytes) {
  websocketpp::lib::error_code ec;
  endpoint_.send(handle_, bytes, websocketpp::frame::opcode::binary, ec);
}

json Client::wait_for(const std::function<bool(const json&)>& pick,
                      std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  std::unique_lock lock(mutex_);
  while (true) {
    while (!texts_.empty()) {
      json m = std::move(texts_.front());
      texts_.pop_front();
      if (pick(m)) return m;
    }
    if (changed_.wait_until(lock, end) == std::cv_status::timeout && texts_.empty()) return {};
  }
}

json Client::request(json message, std::chrono::milliseconds timeout) {
  const int id = next_id_++;
  message["id"] = id;
  send_text(message.dump());
  return wait_for([id](const json& m) { return m.is_object() && m.value("id", -1) == id; },
                  timeout);
}

json Client::state(int node) {
  json m = {{"op", "state"}};
  if (node >= 0) m["node"] = node;
  return request(m);
}

long Client::frames() const {
  std::lock_guard lock(mutex_);
  return frames_;
}

std::string Client::first_binary() const {
  std::lock_guard lock(mutex_);
  return first_binary_;
}

std::string Client::last_frame() const {
  std::lock_guard lock(mutex_);
  return last_frame_;
}

int Client::close_code() const {
  std::lock_guard lock(mutex_);
  return close_code_;
}

void Client::close() {
  if (!thread_.joinable()) return;
  websocketpp::lib::error_code ec;
  endpoint_.close(handle_, websocketpp::close::status::normal, "", ec);
  // A server that never answers: the client gives up after its close timeout (5 s).
  thread_.join();
}

}  // namespace phymul::testing
