// phymul serve as a user meets it, and as an attacker would: its command line, who may
// connect, what HTTP serves, and stopping with Ctrl-C.
#include <gtest/gtest.h>

#include <asio.hpp>

#include "serve_client.hpp"

namespace phymul::testing {
namespace {

const std::string kBlock = "tests/data/serve/block.yaml";

// A raw HTTP request (the request line and headers, verbatim) and the whole reply.
std::string http(int port, const std::string& request) {
  asio::io_context io;
  asio::ip::tcp::socket socket(io);
  socket.connect({asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)});
  asio::write(socket, asio::buffer(request));
  std::string reply;
  std::array<char, 65536> buffer{};
  asio::error_code ec;
  while (size_t n = socket.read_some(asio::buffer(buffer), ec)) reply.append(buffer.data(), n);
  return reply;
}

std::string status_line(const std::string& reply) { return reply.substr(0, reply.find("\r\n")); }

TEST(ServeCli, BadArgumentsAndBadScenesExitWithAClearError) {
  Finished f = run_cli({"serve", scene_path(kBlock), "--host", "0.0.0.0"});
  EXPECT_EQ(f.exit_code, 1);
  EXPECT_NE(f.output.find("give --token"), std::string::npos) << f.output;
  f = run_cli({"serve", scene_path(kBlock), "--host", "0.0.0.0", "--token", "short"});
  EXPECT_EQ(f.exit_code, 1);
  EXPECT_NE(f.output.find("--token must be 8 to 256"), std::string::npos) << f.output;
  f = run_cli({"serve", scene_path(kBlock), "--port", "70000"});
  EXPECT_NE(f.exit_code, 0);
  EXPECT_NE(f.output.find("--port"), std::string::npos) << f.output;
  f = run_cli({"serve", scene_path("tests/data/bad_scenes/negative_stiffness.yaml")});
  EXPECT_EQ(f.exit_code, 1);
  EXPECT_NE(f.output.find("negative_stiffness.yaml:"), std::string::npos) << f.output;
  f = run_cli({"serve", scene_path("examples/compressed_cube.yaml")});
  EXPECT_EQ(f.exit_code, 1);
  EXPECT_NE(f.output.find("is a static scene"), std::string::npos) << f.output;
  f = run_cli({"serve", "/nonexistent/scene.yaml"});
  EXPECT_EQ(f.exit_code, 1);
  EXPECT_NE(f.output.find("/nonexistent/scene.yaml"), std::string::npos) << f.output;
}

TEST(ServeCli, APortInUseIsSaidAndExits1) {
  ServerProcess first({scene_path(kBlock), "--port", "0", "--threads", "1"});
  const Finished f = run_cli({"serve", scene_path(kBlock), "--port", std::to_string(first.port())});
  EXPECT_EQ(f.exit_code, 1);
  EXPECT_NE(f.output.find("cannot listen on 127.0.0.1:" + std::to_string(first.port())),
            std::string::npos)
      << f.output;
}

TEST(ServeSecurity, ServesItsFixedFilesAndNothingElse) {
  ServerProcess server({scene_path(kBlock), "--port", "0", "--threads", "1"});
  const int port = server.port();
  const std::string page = http(port, "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  EXPECT_EQ(status_line(page), "HTTP/1.1 200 OK");
  EXPECT_NE(page.find("<html"), std::string::npos);
  for (const char* path :
       {"/../../../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd", "/CMakeCache.txt",
        "/share/phymul/web/app.js", "//etc/passwd", "/ws/../app.js"}) {
    const std::string reply =
        http(port, std::string("GET ") + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
    EXPECT_EQ(status_line(reply), "HTTP/1.1 404 Not Found") << path;
    EXPECT_EQ(reply.find("root:"), std::string::npos);
  }
  EXPECT_EQ(
      status_line(http(port, "POST / HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 2\r\n\r\nhi")),
      "HTTP/1.1 405 Method Not Allowed");
  const std::string garbage = http(port, "\x01\x02 nonsense\r\n\r\n");
  EXPECT_EQ(garbage.find("200 OK"), std::string::npos);
  // Still serving.
  Client client;
  EXPECT_EQ(client.connect(port), "");
}

TEST(ServeSecurity, OnlyPagesOfThisServerUnderALoopbackNameMayConnect) {
  ServerProcess server({scene_path(kBlock), "--port", "0", "--threads", "1"});
  const int port = server.port();
  const std::string self = "127.0.0.1:" + std::to_string(port);
  Client page, other_site, rebound, elsewhere;
  EXPECT_EQ(page.connect(port, "/ws", {{"Origin", "http://" + self}}), "");
  EXPECT_NE(other_site.connect(port, "/ws", {{"Origin", "http://evil.example"}}).find("HTTP 403"),
            std::string::npos);
  // DNS rebinding: a site whose name now points at 127.0.0.1.
  EXPECT_NE(rebound
                .connect(port, "/ws",
                         {{"Host", "evil.example:" + std::to_string(port)},
                          {"Origin", "http://evil.example:" + std::to_string(port)}})
                .find("HTTP 403"),
            std::string::npos);
  EXPECT_NE(elsewhere.connect(port, "/stream").find("HTTP 403"), std::string::npos);
}

TEST(ServeSecurity, WithATokenOnlyClientsThatGiveItConnect) {
  const std::string token = "s3cret-token_42";
  ServerProcess server({scene_path(kBlock), "--port", "0", "--threads", "1", "--host", "127.0.0.1",
                        "--token", token});
  EXPECT_NE(server.banner().find("?token=" + token), std::string::npos);
  Client without, wrong, right;
  EXPECT_NE(without.connect(server.port(), "/ws").find("HTTP 403"), std::string::npos);
  EXPECT_NE(wrong.connect(server.port(), "/ws?token=s3cret-token_43").find("HTTP 403"),
            std::string::npos);
  EXPECT_EQ(right.connect(server.port(), "/ws?token=" + token), "");
  EXPECT_TRUE(right.state().value("type", "") == "state");
}

TEST(ServeSignals, CtrlCStopsTheServerCleanlyWithClientsConnected) {
  ServerProcess server({scene_path(kBlock), "--port", "0", "--threads", "1"});
  Client a, b;
  ASSERT_EQ(a.connect(server.port()), "");
  ASSERT_EQ(b.connect(server.port()), "");
  b.close();  // a page closed: the server runs on
  std::this_thread::sleep_for(200ms);
  EXPECT_EQ(a.state().value("type", ""), "state");
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(server.stop(SIGINT), 0);
  EXPECT_LT(std::chrono::steady_clock::now() - start, 3s);
  for (int k = 0; k < 200 && a.close_code() == 0; ++k) std::this_thread::sleep_for(10ms);
  EXPECT_EQ(a.close_code(), 1001);  // going away
}

}  // namespace
}  // namespace phymul::testing
