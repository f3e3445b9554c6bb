// websocketpp over standalone asio (ASIO_STANDALONE): the protocol work is theirs; this file
// only maps connections to ids and the handlers of websocket_server.hpp.
#include "websocket_server.hpp"

#include <csignal>
#include <map>
#include <stdexcept>
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

namespace phymul::serve {

using Endpoint = websocketpp::server<websocketpp::config::asio>;
using Handle = websocketpp::connection_hdl;

struct WebSocketServer::Impl {
  // Declared before the asio objects, so destroyed after them: destroying those may still
  // close connections, whose handlers read these.
  ServerHandlers handlers;
  std::map<ClientId, Handle> clients;
  std::map<Handle, ClientId, std::owner_less<Handle>> ids;
  ClientId next_id = 1;
  bool stopping = false, signalled = false, dying = false;
  std::chrono::milliseconds tick{16};
  asio::io_context io;
  Endpoint endpoint;
  asio::steady_timer ticker{io}, deadline{io};
  asio::signal_set signals{io, SIGINT, SIGTERM};

  ClientId id_of(const Handle& h) const {
    const auto it = ids.find(h);
    return it == ids.end() ? 0 : it->second;
  }
  Endpoint::connection_ptr connection(ClientId client) const {
    const auto it = clients.find(client);
    if (it == clients.end()) return nullptr;
    asio::error_code ec;
    Endpoint::connection_ptr c = const_cast<Endpoint&>(endpoint).get_con_from_hdl(it->second, ec);
    return ec ? nullptr : c;
  }
  void forget(const Handle& h) {
    const ClientId id = id_of(h);
    if (id == 0 || dying) return;
    ids.erase(h);
    clients.erase(id);
    if (handlers.close) handlers.close(id);
    if (stopping && clients.empty()) io.stop();
  }
  void schedule_tick() {
    ticker.expires_after(tick);
    ticker.async_wait([this](const asio::error_code& ec) {
      if (ec || stopping) return;
      if (handlers.tick) handlers.tick();
      schedule_tick();
    });
  }
  void install();
};

void WebSocketServer::Impl::install() {
  endpoint.clear_access_channels(websocketpp::log::alevel::all);
  endpoint.clear_error_channels(websocketpp::log::elevel::all);
  endpoint.init_asio(&io);
  endpoint.set_reuse_addr(true);
  endpoint.set_socket_init_handler([](Handle, asio::ip::tcp::socket& s) {
    asio::error_code ec;
    s.set_option(asio::ip::tcp::no_delay(true), ec);  // frames go out as they are sent
  });
  endpoint.set_validate_handler([this](Handle h) {
    Endpoint::connection_ptr c = endpoint.get_con_from_hdl(h);
    const std::string why = handlers.accept(
        {c->get_resource(), c->get_request_header("Host"), c->get_request_header("Origin")});
    if (why.empty()) return true;
    c->set_status(websocketpp::http::status_code::forbidden);
    c->set_body(why);
    return false;
  });
  endpoint.set_open_handler([this](Handle h) {
    const ClientId id = next_id++;
    clients[id] = h;
    ids[h] = id;
    if (handlers.open) handlers.open(id);
  });
  endpoint.set_close_handler([this](Handle h) { forget(h); });
  endpoint.set_fail_handler([this](Handle h) { forget(h); });
  endpoint.set_message_handler([this](Handle h, Endpoint::message_ptr m) {
    const ClientId id = id_of(h);
    if (id == 0) return;
    if (m->get_opcode() == websocketpp::frame::opcode::text)
      handlers.text(id, m->get_payload());
    else
      handlers.binary(id, m->get_payload().size());
  });
  endpoint.set_http_handler([this](Handle h) {
    Endpoint::connection_ptr c = endpoint.get_con_from_hdl(h);
    const HttpReply r = handlers.http(c->get_request().get_method(), c->get_resource());
    c->set_status(static_cast<websocketpp::http::status_code::value>(r.status));
    c->append_header("Content-Type", r.content_type);
    c->append_header("Cache-Control", "no-store");
    c->append_header("X-Content-Type-Options", "nosniff");
    c->set_body(r.body);
  });
}

WebSocketServer::WebSocketServer(ServerHandlers handlers, std::size_t max_message_bytes,
                                 std::size_t send_buffer_bytes)
    : impl_(std::make_unique<Impl>()) {
  impl_->handlers = std::move(handlers);
  impl_->install();
  // Once accepted (the socket exists from then on): without this the kernel grows a send
  // buffer to megabytes, seconds of stale frames for a client that reads slowly.
  Impl& s = *impl_;
  s.endpoint.set_tcp_post_init_handler([&s, send_buffer_bytes](Handle h) {
    asio::error_code ec;
    s.endpoint.get_con_from_hdl(h)->get_socket().set_option(
        asio::socket_base::send_buffer_size(int(send_buffer_bytes)), ec);
  });
  impl_->endpoint.set_max_message_size(max_message_bytes);
  impl_->endpoint.set_max_http_body_size(max_message_bytes);
}

// The connections still open go with the endpoint, telling no one: the handlers' owner may be
// half destroyed by now.
WebSocketServer::~WebSocketServer() { impl_->dying = true; }

int WebSocketServer::listen(const std::string& host, int port) {
  asio::error_code ec;
  asio::ip::tcp::resolver resolver(impl_->io);
  const auto found = resolver.resolve(host, std::to_string(port), ec);
  if (ec || found.empty())
    throw std::runtime_error("cannot resolve host '" + host + "': " + ec.message());
  impl_->endpoint.listen(found.begin()->endpoint(), ec);
  if (ec)
    throw std::runtime_error("cannot listen on " + host + ":" + std::to_string(port) + ": " +
                             ec.message());
  impl_->endpoint.start_accept(ec);
  if (ec) throw std::runtime_error("cannot accept connections: " + ec.message());
  const asio::ip::tcp::endpoint local = impl_->endpoint.get_local_endpoint(ec);
  if (ec) throw std::runtime_error("cannot read the port bound: " + ec.message());
  return local.port();
}

void WebSocketServer::run(std::chrono::milliseconds tick) {
  impl_->tick = tick;
  impl_->signals.async_wait([this](const asio::error_code& ec, int) {
    if (ec) return;
    impl_->signalled = true;
    stop();
  });
  impl_->schedule_tick();
  impl_->io.run();
}

void WebSocketServer::stop() {
  Impl& s = *impl_;
  if (s.stopping) return;
  s.stopping = true;
  asio::error_code ec;
  s.ticker.cancel();
  s.signals.clear(ec);  // a second Ctrl-C ends the process at once
  s.endpoint.stop_listening(ec);
  for (const auto& [id, h] : s.clients)
    s.endpoint.close(h, websocketpp::close::status::going_away, "server stopping", ec);
  if (s.clients.empty()) s.io.stop();
  // Clients that never answer the close: the server ends anyway.
  s.deadline.expires_after(std::chrono::seconds(2));
  s.deadline.async_wait([&s](const asio::error_code& e) {
    if (!e) s.io.stop();
  });
}

bool WebSocketServer::send_text(ClientId client, const std::string& text) {
  const Endpoint::connection_ptr c = impl_->connection(client);
  return c && !c->send(text, websocketpp::frame::opcode::text);
}

bool WebSocketServer::send_binary(ClientId client, const void* data, std::size_t bytes) {
  const Endpoint::connection_ptr c = impl_->connection(client);
  return c && !c->send(data, bytes, websocketpp::frame::opcode::binary);
}

std::size_t WebSocketServer::buffered(ClientId client) const {
  const Endpoint::connection_ptr c = impl_->connection(client);
  return c ? c->get_buffered_amount() : 0;
}

void WebSocketServer::close(ClientId client, std::uint16_t code, const std::string& reason) {
  const Endpoint::connection_ptr c = impl_->connection(client);
  asio::error_code ec;
  if (c) c->close(code, reason, ec);
}

bool WebSocketServer::signalled() const { return impl_->signalled; }

}  // namespace phymul::serve
