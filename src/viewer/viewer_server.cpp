// Viewer module: HTTP routes, token and host checks, WebSocket connections with bounded queues.
#include "texgrad/viewer/viewer_server.h"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <cstring>
#include <deque>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>

#include "texgrad/core/error.h"
#include "texgrad/viewer/access_token.h"

namespace texgrad::viewer {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

/// Request header bytes accepted (the page's requests are a few hundred bytes).
constexpr uint32_t kMaxHeaderBytes = 8 * 1024;
/// Seconds a client has to send a complete HTTP request.
constexpr int kRequestTimeoutSeconds = 30;
/// Text replies queued for one connection beyond which it is closed (a client not reading).
constexpr size_t kMaxQueuedReplies = 512;

std::string str(beast::string_view s) {
  return std::string(s.data(), s.size());
}

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw IoError("viewer page file " + path.string() +
                  " not found: build the page with scripts/build-viewer.sh or pass --web-root");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Host part of a Host header ("127.0.0.1:8080" -> "127.0.0.1", "[::1]:80" -> "::1").
std::string hostName(std::string_view header) {
  if (!header.empty() && header.front() == '[') {
    const size_t close = header.find(']');
    return std::string(header.substr(1, close == std::string_view::npos ? 0 : close - 1));
  }
  return std::string(header.substr(0, header.find(':')));
}

class WsConnection;

/// State shared by the listener, the connections and the session's frame sink.
struct Core {
  explicit Core(ViewerSession& s) : session(s) {}
  ViewerSession& session;
  net::io_context ioc{1};
  std::string token;
  bool loopback = true;
  int maxConnections = 16;
  std::string index, script, info, mesh;
  std::mutex mutex;
  std::vector<std::weak_ptr<WsConnection>> sockets;

  int liveSockets() {
    std::lock_guard lock(mutex);
    std::erase_if(sockets, [](const auto& w) { return w.expired(); });
    return static_cast<int>(sockets.size());
  }
};

class WsConnection : public std::enable_shared_from_this<WsConnection> {
 public:
  WsConnection(tcp::socket&& socket, Core* core) : ws_(std::move(socket)), core_(core) {}

  void accept(http::request<http::empty_body> request) {
    beast::get_lowest_layer(ws_).expires_never();
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(kMaxFrameBytes);
    // One websocket frame per message: Beast's default cuts each 2 MB texture into 4 KB frames,
    // one system call and one wake-up of the page's network thread each.
    ws_.auto_fragment(false);
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) {
      if (!ec) self->onAccept();
    });
  }

  /// Queues a frame, replacing a queued frame that has not started writing (latest wins).
  void queueFrame(SharedBytes frame) {
    for (size_t i = writing_ ? 1 : 0; i < queue_.size(); ++i)
      if (queue_[i].binary) {
        queue_[i].bytes = std::move(frame);
        return;
      }
    queue_.push_back({true, std::move(frame), {}});
    write();
  }

  void queueText(std::string text) {
    if (queue_.size() > kMaxQueuedReplies) {
      beast::get_lowest_layer(ws_).close();
      return;
    }
    queue_.push_back({false, nullptr, std::move(text)});
    write();
  }

  net::any_io_executor executor() { return ws_.get_executor(); }

 private:
  struct Out {
    bool binary;
    SharedBytes bytes;
    std::string text;
  };

  void onAccept() {
    {
      std::lock_guard lock(core_->mutex);
      core_->sockets.push_back(weak_from_this());
    }
    queueText(core_->session.stateJson());
    queueFrame(core_->session.latestFrame());
    read();
  }

  void read() {
    ws_.async_read(buffer_,
                   [self = shared_from_this()](beast::error_code ec, size_t) { self->onRead(ec); });
  }

  void onRead(beast::error_code ec) {
    if (ec) return;  // closed, or too big (Beast answers 1009 and closes)
    if (ws_.got_binary()) {
      queueText(errorReply("binary messages are not accepted; send JSON text"));
    } else {
      const auto data = buffer_.cdata();
      const std::string_view text(static_cast<const char*>(data.data()), data.size());
      std::weak_ptr<WsConnection> weak = weak_from_this();
      core_->session.receive(text, [weak](std::string reply) {
        if (auto self = weak.lock())
          net::post(self->executor(),
                    [self, r = std::move(reply)]() mutable { self->queueText(std::move(r)); });
      });
    }
    buffer_.consume(buffer_.size());
    read();
  }

  void write() {
    if (writing_ || queue_.empty()) return;
    writing_ = true;
    Out& out = queue_.front();
    ws_.binary(out.binary);
    const net::const_buffer buffer = out.binary
                                         ? net::const_buffer(out.bytes->data(), out.bytes->size())
                                         : net::const_buffer(out.text.data(), out.text.size());
    ws_.async_write(buffer, [self = shared_from_this()](beast::error_code ec, size_t) {
      self->writing_ = false;
      self->queue_.pop_front();
      if (!ec) self->write();
    });
  }

  websocket::stream<beast::tcp_stream> ws_;
  Core* core_;  ///< owned by the server, outlives every connection (they live in its io_context)
  beast::flat_buffer buffer_;
  std::deque<Out> queue_;
  bool writing_ = false;
};

class HttpConnection : public std::enable_shared_from_this<HttpConnection> {
 public:
  HttpConnection(tcp::socket&& socket, Core* core) : stream_(std::move(socket)), core_(core) {}

  void read() {
    parser_.emplace();
    parser_->header_limit(kMaxHeaderBytes);
    parser_->body_limit(0);
    stream_.expires_after(std::chrono::seconds(kRequestTimeoutSeconds));
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, size_t) {
                       if (ec) return self->close();
                       self->onRequest();
                     });
  }

 private:
  using Response = http::response<http::string_body>;

  void close() {
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
  }

  /// Why a request is refused before routing, or empty.
  std::pair<http::status, std::string> refusal(const http::request<http::empty_body>& req) const {
    const std::string target = str(req.target());
    if (!tokenMatches(queryParameter(target, "token"), core_->token))
      return {http::status::forbidden, "missing or wrong access token"};
    const std::string host = hostName(str(req[http::field::host]));
    if (core_->loopback && !isLoopbackHost(host))
      return {http::status::forbidden, "this server answers only to localhost host names"};
    const std::string origin = str(req[http::field::origin]);
    if (!origin.empty() && origin != "http://" + str(req[http::field::host]))
      return {http::status::forbidden, "cross-origin requests are not served"};
    return {http::status::ok, {}};
  }

  void onRequest() {
    http::request<http::empty_body> req = parser_->release();
    const auto [status, reason] = refusal(req);
    if (status != http::status::ok) return respond(req, status, "text/plain", reason + "\n");
    const std::string path(targetPath(str(req.target())));
    if (websocket::is_upgrade(req)) {
      if (path != "/ws") return respond(req, http::status::not_found, "text/plain", "not found\n");
      if (core_->liveSockets() >= core_->maxConnections)
        return respond(req, http::status::service_unavailable, "text/plain",
                       "too many viewer connections\n");
      std::make_shared<WsConnection>(stream_.release_socket(), core_)->accept(std::move(req));
      return;
    }
    if (req.method() != http::verb::get && req.method() != http::verb::head)
      return respond(req, http::status::method_not_allowed, "text/plain", "only GET\n");
    if (path == "/" || path == "/index.html")
      return respond(req, http::status::ok, "text/html; charset=utf-8", core_->index);
    if (path == "/viewer.js")
      return respond(req, http::status::ok, "text/javascript; charset=utf-8", core_->script);
    if (path == "/api/info") return respond(req, http::status::ok, "application/json", core_->info);
    if (path == "/api/mesh")
      return respond(req, http::status::ok, "application/octet-stream", core_->mesh);
    respond(req, http::status::not_found, "text/plain", "not found\n");
  }

  void respond(const http::request<http::empty_body>& req, http::status status, const char* type,
               const std::string& body) {
    auto res = std::make_shared<Response>(status, req.version());
    res->set(http::field::server, "texgrad-view");
    res->set(http::field::content_type, type);
    res->set(http::field::cache_control, "no-store");
    res->set("X-Content-Type-Options", "nosniff");
    res->set("Content-Security-Policy",
             "default-src 'self'; connect-src 'self'; img-src 'self' data: blob:; "
             "style-src 'self' 'unsafe-inline'");
    res->keep_alive(req.keep_alive() && status == http::status::ok);
    if (req.method() != http::verb::head) res->body() = body;
    res->prepare_payload();
    if (req.method() == http::verb::head) res->content_length(body.size());
    http::async_write(stream_, *res,
                      [self = shared_from_this(), res](beast::error_code ec, size_t) {
                        if (ec || !res->keep_alive()) return self->close();
                        self->read();
                      });
  }

  beast::tcp_stream stream_;
  Core* core_;  ///< owned by the server, outlives every connection (they live in its io_context)
  beast::flat_buffer buffer_{kMaxHeaderBytes};
  std::optional<http::request_parser<http::empty_body>> parser_;
};

}  // namespace

void ServerOptions::validate() const {
  if (host.empty()) throw InvalidInputError("host must not be empty");
  if (maxConnections < 1) throw InvalidInputError("maxConnections must be at least 1");
}

std::vector<uint8_t> encodeMesh(const TexturedMesh& mesh) {
  const auto f = static_cast<uint32_t>(mesh.faceCount());
  const auto v = static_cast<uint32_t>(mesh.positions.size());
  std::vector<uint8_t> out;
  out.reserve(16 + 12 * size_t{f} + 12 * size_t{v} + 24 * size_t{f});
  const auto put = [&out](const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  };
  const uint32_t header[4] = {0x314d4754u /* "TGM1" */, f, v, 0};
  put(header, sizeof header);
  for (const auto& t : mesh.triangles)
    for (int32_t i : t) {
      const auto u = static_cast<uint32_t>(i);
      put(&u, 4);
    }
  for (const auto& p : mesh.positions)
    for (int k = 0; k < 3; ++k) {
      const auto x = static_cast<float>(p[k]);
      put(&x, 4);
    }
  for (const auto& t : mesh.uvTriangles)
    for (int32_t i : t)
      for (int k = 0; k < 2; ++k) {
        const auto x = static_cast<float>(mesh.uvs[i][k]);
        put(&x, 4);
      }
  return out;
}

struct ViewerServer::Impl {
  std::shared_ptr<Core> core;
  std::unique_ptr<tcp::acceptor> acceptor;
  ServerOptions options;

  void acceptNext() {
    acceptor->async_accept(
        net::make_strand(core->ioc), [this](beast::error_code ec, tcp::socket socket) {
          if (ec) return;  // acceptor closed
          std::make_shared<HttpConnection>(std::move(socket), core.get())->read();
          acceptNext();
        });
  }
};

ViewerServer::ViewerServer(ViewerSession& session, const TexelDomain& domain,
                           const ServerOptions& options)
    : impl_(std::make_shared<Impl>()) {
  options.validate();
  impl_->options = options;
  auto core = std::make_shared<Core>(session);
  impl_->core = core;
  core->loopback = isLoopbackHost(options.host);
  if (!core->loopback) core->token = generateAccessToken();
  core->maxConnections = options.maxConnections;
  core->index = readFile(options.webRoot / "index.html");
  if (!core->token.empty()) {
    // The page's own script request must carry the token too.
    const std::string script = "src=\"viewer.js\"";
    const size_t at = core->index.find(script);
    if (at != std::string::npos)
      core->index.replace(at, script.size(), "src=\"viewer.js?token=" + core->token + "\"");
  }
  core->script = readFile(options.webRoot / "viewer.js");
  const std::vector<uint8_t> mesh = encodeMesh(domain.mesh());
  core->mesh.assign(mesh.begin(), mesh.end());
  const SessionState state = session.state();
  core->info = nlohmann::json{{"app", state.app},
                              {"width", domain.grid().imageWidth},
                              {"height", domain.grid().imageHeight},
                              {"faces", domain.mesh().faceCount()},
                              {"unknowns", domain.unknowns()}}
                   .dump();

  beast::error_code ec;
  const auto address =
      net::ip::make_address(options.host == "localhost" ? "127.0.0.1" : options.host, ec);
  if (ec)
    throw InvalidInputError("host \"" + options.host + "\" is not an IP address or localhost");
  const tcp::endpoint endpoint(address, options.port);
  impl_->acceptor = std::make_unique<tcp::acceptor>(core->ioc);
  impl_->acceptor->open(endpoint.protocol(), ec);
  if (!ec) impl_->acceptor->set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) impl_->acceptor->bind(endpoint, ec);
  if (!ec) impl_->acceptor->listen(net::socket_base::max_listen_connections, ec);
  if (ec)
    throw IoError("cannot listen on " + options.host + ":" + std::to_string(options.port) + ": " +
                  ec.message() + " (try another --port)");

  session.setFrameSink([core](SharedBytes frame) {
    std::vector<std::shared_ptr<WsConnection>> live;
    {
      std::lock_guard lock(core->mutex);
      for (const auto& w : core->sockets)
        if (auto s = w.lock()) live.push_back(std::move(s));
    }
    for (auto& s : live) net::post(s->executor(), [s, frame] { s->queueFrame(frame); });
  });
  impl_->acceptNext();
}

ViewerServer::~ViewerServer() {
  impl_->core->session.setFrameSink({});
  stop();
}

uint16_t ViewerServer::port() const {
  return impl_->acceptor->local_endpoint().port();
}

const std::string& ViewerServer::token() const {
  return impl_->core->token;
}

std::string ViewerServer::url() const {
  const std::string& host = impl_->options.host;
  const bool v6 = host.find(':') != std::string::npos;
  std::string url = "http://" + (v6 ? "[" + host + "]" : host) + ":" + std::to_string(port()) + "/";
  if (!token().empty()) url += "?token=" + token();
  return url;
}

void ViewerServer::run() {
  net::signal_set signals(impl_->core->ioc, SIGINT, SIGTERM);
  signals.async_wait([this](beast::error_code, int) { stop(); });
  impl_->core->ioc.run();
}

void ViewerServer::stop() {
  impl_->core->ioc.stop();
}

}  // namespace texgrad::viewer
