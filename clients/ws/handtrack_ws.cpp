// handtrack-ws: the browser bridge (SPEC.md "Programs", docs/WEBSOCKET.md). It reads the pose ring
// like any client and serves, on 127.0.0.1:8765 unless told otherwise:
//   GET /          a page that draws the live hand (page/index.html, built in)
//   GET /poses     a WebSocket: one text message per frame, the JSON object handtrack-cat prints
//                  (every hand of the frame in "hands")
//
// A WebSocket whose Origin is not on the allow-list (the page's own origins, plus --allow-origin)
// is refused with 403: a web page elsewhere must not read the user's hands. A slow browser never
// slows the reader or the other browsers: each connection writes the newest frame when its
// previous write has completed, and drops what came in between. Messages are bounded (a frame is
// about 5 KB per hand; a browser may send at most 1 KB, which is read and ignored), and so are connections.
//
// Thread roles: two threads. The reader thread turns frames from the ring into messages and posts
// each to the network thread; the network thread (Boost.Asio's io_context) runs every connection.
// Nothing else is shared.
#include <handtrack/client.hpp>

#include "handtrack/common/cli.hpp"
#include "pose_json.hpp"

#include <CLI/CLI.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace handtrack::ws {
extern const char* const kPage;  // page/index.html, built in by CMake (index_html.cpp.in)
}  // namespace handtrack::ws

namespace {

using handtrack::ws::kPage;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using Message = std::shared_ptr<const std::string>;

constexpr const char* kProgram = "handtrack-ws";
constexpr std::size_t kMaxIncomingBytes = 1024;      // browsers have nothing to tell us
constexpr std::uint32_t kMaxRequestBytes = 8 * 1024;  // an HTTP request, headers included
constexpr auto kHttpTimeout = std::chrono::seconds(10);

struct Options {
  std::string shm_name = HANDTRACK_DEFAULT_SHM_NAME;
  std::string listen = "127.0.0.1";
  unsigned short port = 8765;
  std::vector<std::string> allowed_origins;  // besides the page's own
  std::size_t max_clients = 32;
  bool smooth = false;
};

class WsSession;

// The open WebSockets; lives on the network thread only.
class Hub {
 public:
  explicit Hub(std::size_t max_clients) : max_clients_(max_clients) {}
  [[nodiscard]] bool full() const { return sessions_.size() >= max_clients_; }
  void join(const std::shared_ptr<WsSession>& s) { sessions_.insert(s); }
  void leave(const std::shared_ptr<WsSession>& s) { sessions_.erase(s); }
  void broadcast(const Message& message);

 private:
  std::size_t max_clients_;
  std::set<std::shared_ptr<WsSession>> sessions_;
};

class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(tcp::socket&& socket, Hub& hub) : ws_(std::move(socket)), hub_(hub) {}

  void start(http::request<http::string_body> request) {
    ws_.read_message_max(kMaxIncomingBytes);
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      self->hub_.join(self);
      self->read();
    });
  }

  // The newest pose: written now if the connection is idle, else after the write in flight,
  // replacing any pose that was waiting (drop to the newest).
  void offer(const Message& message) {
    if (sending_) {
      pending_ = message;
      return;
    }
    send(message);
  }

 private:
  void read() {
    ws_.async_read(incoming_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) {
        self->hub_.leave(self);
        return;
      }
      self->incoming_.clear();
      self->read();
    });
  }

  void send(const Message& message) {
    sending_ = message;
    ws_.text(true);
    ws_.async_write(net::buffer(*sending_), [self = shared_from_this()](beast::error_code ec, std::size_t) {
      self->sending_.reset();
      if (ec) {
        self->hub_.leave(self);
        return;
      }
      if (self->pending_) self->send(std::exchange(self->pending_, nullptr));
    });
  }

  websocket::stream<beast::tcp_stream> ws_;
  Hub& hub_;
  beast::flat_buffer incoming_;
  Message sending_;
  Message pending_;
};

void Hub::broadcast(const Message& message) {
  for (const auto& s : sessions_) s->offer(message);
}

// One HTTP request: the page, or the upgrade to a WebSocket.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket&& socket, Hub& hub, const std::vector<std::string>& origins)
      : stream_(std::move(socket)), hub_(hub), origins_(origins) {}

  void start() {
    parser_.header_limit(kMaxRequestBytes);
    parser_.body_limit(kMaxRequestBytes);
    stream_.expires_after(kHttpTimeout);
    http::async_read(stream_, buffer_, parser_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (!ec) self->answer(self->parser_.release());
    });
  }

 private:
  void answer(http::request<http::string_body> request) {
    if (websocket::is_upgrade(request)) {
      if (request.target() != "/poses") return reply(request, http::status::not_found, "no such WebSocket\n");
      const auto origin = request[http::field::origin];
      // Browsers always send an Origin; a local program without one could read the ring anyway.
      if (!origin.empty() && std::find(origins_.begin(), origins_.end(), origin) == origins_.end()) {
        return reply(request, http::status::forbidden, "origin not allowed\n");
      }
      if (hub_.full()) return reply(request, http::status::service_unavailable, "too many connections\n");
      stream_.expires_never();
      std::make_shared<WsSession>(stream_.release_socket(), hub_)->start(std::move(request));
      return;
    }
    if (request.method() != http::verb::get) return reply(request, http::status::method_not_allowed, "GET only\n");
    if (request.target() == "/" || request.target() == "/index.html") {
      return reply(request, http::status::ok, kPage, "text/html; charset=utf-8");
    }
    reply(request, http::status::not_found, "not found\n");
  }

  void reply(const http::request<http::string_body>& request, http::status status, const std::string& body,
             const char* type = "text/plain; charset=utf-8") {
    auto response = std::make_shared<http::response<http::string_body>>(status, request.version());
    response->set(http::field::server, kProgram);
    response->set(http::field::content_type, type);
    response->set(http::field::cache_control, "no-store");
    response->keep_alive(false);
    response->body() = body;
    response->prepare_payload();
    http::async_write(stream_, *response, [self = shared_from_this(), response](beast::error_code, std::size_t) {
      beast::error_code ignored;
      self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
    });
  }

  beast::tcp_stream stream_;
  Hub& hub_;
  const std::vector<std::string>& origins_;
  beast::flat_buffer buffer_;
  http::request_parser<http::string_body> parser_;
};

class Listener : public std::enable_shared_from_this<Listener> {
 public:
  Listener(net::io_context& io, const tcp::endpoint& at, Hub& hub, const std::vector<std::string>& origins)
      : io_(io), acceptor_(io), hub_(hub), origins_(origins) {
    acceptor_.open(at.protocol());
    acceptor_.set_option(net::socket_base::reuse_address(true));
    acceptor_.bind(at);
    acceptor_.listen(net::socket_base::max_listen_connections);
  }
  [[nodiscard]] unsigned short port() const { return acceptor_.local_endpoint().port(); }
  void accept() {
    acceptor_.async_accept(net::make_strand(io_), [self = shared_from_this()](beast::error_code ec, tcp::socket s) {
      if (!ec) std::make_shared<HttpSession>(std::move(s), self->hub_, self->origins_)->start();
      self->accept();
    });
  }

 private:
  net::io_context& io_;
  tcp::acceptor acceptor_;
  Hub& hub_;
  const std::vector<std::string>& origins_;
};

// The reader thread: the newest frame of the ring, as a message, to the network thread. Waits for
// the daemon to appear and follows its restarts (the client library reattaches by itself).
void read_poses(const Options& options, net::io_context& io, Hub& hub, const std::atomic<bool>& stop) {
  handtrack::Client client;
  handtrack::PoseFilter filter;
  handtrack::json::Line line;
  handtrack_frame frame{};
  bool reported = false;
  while (!stop.load(std::memory_order_relaxed)) {
    if (!client.is_open()) {
      if (const int st = client.open(options.shm_name); st != HANDTRACK_OK) {
        if (!reported) std::fprintf(stderr, "%s: waiting for poses: %s\n", kProgram, handtrack::Client::describe(st).c_str());
        reported = true;
        std::this_thread::sleep_for(std::chrono::milliseconds(250));
        continue;
      }
      std::fprintf(stderr, "%s: reading poses from /%s\n", kProgram, options.shm_name.c_str());
      reported = false;
    }
    if (client.wait_latest(frame, std::chrono::milliseconds(200)) != HANDTRACK_OK) continue;
    if (options.smooth) filter.apply(frame);
    handtrack::json::format_frame(frame, client.missed(), line);
    auto message = std::make_shared<const std::string>(line.text());
    net::post(io, [&hub, message] { hub.broadcast(message); });
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"handtrack-ws: hand poses as JSON over WebSocket, and a live page that draws the hand."};
  Options options;
  app.add_option("--shm-name", options.shm_name, "shared-memory object name")->capture_default_str();
  app.add_option("--listen", options.listen,
                 "address to listen on (default 127.0.0.1: this machine only; another address exposes the "
                 "user's hands to the network)")
      ->capture_default_str();
  app.add_option("--port", options.port, "TCP port (0: any free one, printed at start)")->capture_default_str();
  app.add_option("--allow-origin", options.allowed_origins,
                 "another web origin allowed to open the WebSocket, e.g. http://localhost:3000 (repeatable)");
  app.add_option("--max-clients", options.max_clients, "WebSocket connections at most")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app.add_flag("--smooth", options.smooth, "smooth poses with the client library's One Euro filter (docs/FILTER.md)");
  if (const auto exit_code = handtrack::parse_command_line(app, argc, argv, kProgram, 1)) return *exit_code;

  try {
    net::io_context io;
    Hub hub(options.max_clients);
    const auto address = net::ip::make_address(options.listen);
    std::vector<std::string> origins = options.allowed_origins;
    auto listener = std::make_shared<Listener>(io, tcp::endpoint(address, options.port), hub, origins);
    const unsigned short port = listener->port();
    for (const char* host : {"127.0.0.1", "localhost", "[::1]"}) {
      origins.push_back("http://" + std::string(host) + ":" + std::to_string(port));
    }
    if (!address.is_loopback()) origins.push_back("http://" + options.listen + ":" + std::to_string(port));
    listener->accept();
    std::printf("%s: serving http://%s:%u/ (poses on ws://%s:%u/poses)\n", kProgram, options.listen.c_str(), port,
                options.listen.c_str(), port);
    std::fflush(stdout);

    std::atomic<bool> stop{false};
    std::thread reader([&] { read_poses(options, io, hub, stop); });
    net::signal_set signals(io, SIGINT, SIGTERM);
    signals.async_wait([&](beast::error_code, int) { io.stop(); });
    io.run();
    stop.store(true, std::memory_order_relaxed);
    reader.join();
    return 0;
  } catch (const std::exception& e) {
    return handtrack::report_error(kProgram, e.what(), 1);
  }
}
