// Viewer module tests: the server end to end over real sockets (Beast client): routes, token and
// host refusal, malformed / oversized WebSocket messages answered while the server keeps serving.
#include <gtest/gtest.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "texgrad/io/procedural.h"
#include "texgrad/viewer/viewer_server.h"

namespace texgrad::viewer {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

/// A running server on a small procedural mesh with a stand-in page.
class RunningServer {
 public:
  explicit RunningServer(const std::string& host, ViewerAppKind kind = ViewerAppKind::Filter)
      : root_(std::filesystem::temp_directory_path() /
              ("texgrad_viewer_test_" + std::to_string(::getpid()))),
        texture_(procedural::sampleTexture(32, 32)),
        domain_(procedural::square(), 32, 32) {
    std::filesystem::create_directories(root_);
    std::ofstream(root_ / "index.html") << "<script src=\"viewer.js\"></script>";
    std::ofstream(root_ / "viewer.js") << "/* page */";
    session_ = std::make_unique<ViewerSession>(makeViewerApp(kind, domain_, texture_, {}),
                                               static_cast<int32_t>(domain_.mesh().faceCount()),
                                               SessionOptions{});
    ServerOptions options;
    options.host = host;
    options.port = 0;
    options.webRoot = root_;
    server_ = std::make_unique<ViewerServer>(*session_, domain_, options);
    session_->start();
    thread_ = std::thread([this] { server_->run(); });
  }
  ~RunningServer() {
    server_->stop();
    thread_.join();
    session_->stop();
    server_.reset();
    std::filesystem::remove_all(root_);
  }
  ViewerServer& server() { return *server_; }
  ViewerSession& session() { return *session_; }
  int faces() const { return static_cast<int>(domain_.mesh().faceCount()); }

 private:
  std::filesystem::path root_;
  Image texture_;
  TexelDomain domain_;
  std::unique_ptr<ViewerSession> session_;
  std::unique_ptr<ViewerServer> server_;
  std::thread thread_;
};

http::response<http::string_body> get(uint16_t port, const std::string& target,
                                      const std::string& host = "127.0.0.1") {
  net::io_context ioc;
  beast::tcp_stream stream(ioc);
  stream.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
  http::request<http::empty_body> req(http::verb::get, target, 11);
  req.set(http::field::host, host + ":" + std::to_string(port));
  http::write(stream, req);
  beast::flat_buffer buffer;
  http::response<http::string_body> res;
  http::read(stream, buffer, res);
  return res;
}

/// A WebSocket client that skips binary frames when waiting for a text reply.
class Client {
 public:
  Client(uint16_t port, const std::string& target) : ws_(ioc_) {
    beast::get_lowest_layer(ws_).connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
    ws_.handshake("127.0.0.1:" + std::to_string(port), target);
  }
  void sendText(const std::string& text) {
    ws_.text(true);
    ws_.write(net::buffer(text));
  }
  void sendBinary(const std::vector<uint8_t>& bytes) {
    ws_.binary(true);
    ws_.write(net::buffer(bytes));
  }
  nlohmann::json nextText() {
    for (;;) {
      beast::flat_buffer buffer;
      ws_.read(buffer);
      if (ws_.got_text()) return nlohmann::json::parse(beast::buffers_to_string(buffer.data()));
      ++frames_;
    }
  }
  int frames() const { return frames_; }
  websocket::stream<beast::tcp_stream>& socket() { return ws_; }

 private:
  net::io_context ioc_;
  websocket::stream<beast::tcp_stream> ws_;
  int frames_ = 0;
};

TEST(ViewerServer, ServesOnlyItsOwnPageAndAsset) {
  RunningServer running("127.0.0.1");
  const uint16_t port = running.server().port();
  EXPECT_TRUE(running.server().token().empty());
  EXPECT_EQ(get(port, "/").result(), http::status::ok);
  EXPECT_EQ(get(port, "/viewer.js").result(), http::status::ok);
  const auto mesh = get(port, "/api/mesh");
  ASSERT_EQ(mesh.result(), http::status::ok);
  EXPECT_EQ(mesh.body().substr(0, 4), "TGM1");
  const auto info = nlohmann::json::parse(get(port, "/api/info").body());
  EXPECT_EQ(info["app"], "filter");
  EXPECT_EQ(info["width"], 32);
  for (const char* target : {"/etc/passwd", "/../CMakeLists.txt", "/index.html/..", "/viewer.js/",
                             "//viewer.js", "/api", "/ws"})
    EXPECT_EQ(get(port, target).result(), http::status::not_found) << target;
  // DNS rebinding: a loopback server answers only to loopback host names.
  EXPECT_EQ(get(port, "/", "evil.example").result(), http::status::forbidden);
  EXPECT_EQ(get(port, "/", "localhost").result(), http::status::ok);
}

TEST(ViewerServer, NonLoopbackBindingRequiresTheToken) {
  RunningServer running("0.0.0.0");
  const uint16_t port = running.server().port();
  const std::string token = running.server().token();
  ASSERT_EQ(token.size(), 32u);
  EXPECT_NE(running.server().url().find("token=" + token), std::string::npos);
  for (const char* target : {"/", "/viewer.js", "/api/mesh", "/api/info", "/?token=wrong"})
    EXPECT_EQ(get(port, target).result(), http::status::forbidden) << target;
  const auto page = get(port, "/?token=" + token);
  ASSERT_EQ(page.result(), http::status::ok);
  EXPECT_NE(page.body().find("viewer.js?token=" + token), std::string::npos);
  EXPECT_EQ(get(port, "/api/mesh?token=" + token).result(), http::status::ok);
  // The WebSocket upgrade is refused without the token, accepted with it.
  EXPECT_THROW(Client(port, "/ws"), beast::system_error);
  Client client(port, "/ws?token=" + token);
  EXPECT_EQ(client.nextText()["type"], "state");
}

TEST(ViewerServer, AnswersBadMessagesAndKeepsServing) {
  RunningServer running("127.0.0.1");
  const uint16_t port = running.server().port();
  Client client(port, "/ws");
  EXPECT_EQ(client.nextText()["type"], "state");  // greeting
  const std::string oversized =
      R"({"type":"state","id":5,"pad":")" + std::string(kMaxMessageBytes, 'x') + "\"}";
  const std::string faceOutOfRange = R"({"type":"source","face":)" +
                                     std::to_string(running.faces()) + R"(,"bary":[1,0,0],"id":6})";
  for (const std::string& bad :
       {std::string("{"), std::string("[[[[[[[[[[]]]]]]]]]]"),
        std::string(R"({"type":"drop tables"})"), oversized, faceOutOfRange}) {
    client.sendText(bad);
    const nlohmann::json reply = client.nextText();
    EXPECT_EQ(reply["type"], "error") << bad.substr(0, 60);
  }
  client.sendBinary({1, 2, 3});
  EXPECT_EQ(client.nextText()["type"], "error");
  // The geodesic message is valid but not for this app: an error from the worker, with the id.
  client.sendText(R"({"type":"source","face":0,"bary":[1,0,0],"id":8})");
  nlohmann::json reply = client.nextText();
  EXPECT_EQ(reply["type"], "error");
  EXPECT_EQ(reply["id"], 8);
  client.sendText(R"({"type":"brush","face":0,"bary":[0.3,0.3,0.4],"radius":0.2,"strength":1,)"
                  R"("mode":"smooth","id":9})");
  reply = client.nextText();
  EXPECT_EQ(reply["type"], "ok");
  EXPECT_EQ(reply["id"], 9);
  client.sendText(R"({"type":"probe","points":[{"face":0,"bary":[0.3,0.3,0.4]}],"id":10})");
  reply = client.nextText();
  ASSERT_EQ(reply["type"], "probe");
  EXPECT_EQ(reply["values"].size(), 1u);
  client.sendText(R"({"type":"save","id":11})");
  EXPECT_EQ(client.nextText()["type"], "error");  // no --out given
  EXPECT_TRUE(running.session().waitSettled(30.0));
  client.sendText(R"({"type":"state","id":12})");
  reply = client.nextText();
  EXPECT_EQ(reply["type"], "state");
  EXPECT_GT(reply["iteration"].get<int>(), 0);
  EXPECT_GE(client.frames(), 1);

  // Beyond the WebSocket layer's limit the connection is closed; the server keeps serving.
  Client flood(port, "/ws");
  EXPECT_EQ(flood.nextText()["type"], "state");
  flood.sendText(std::string(kMaxFrameBytes + 1, ' '));
  EXPECT_THROW(flood.nextText(), beast::system_error);
  Client after(port, "/ws");
  EXPECT_EQ(after.nextText()["type"], "state");
  EXPECT_EQ(get(port, "/").result(), http::status::ok);
}

TEST(ViewerSession, GeodesicSourceRefinesToZeroAtTheSource) {
  const TexelDomain domain(procedural::cubeSphere(6), 64, 64);
  const Image texture(64, 64, 3);
  ViewerSession session(makeViewerApp(ViewerAppKind::Geodesic, domain, texture, {}),
                        static_cast<int32_t>(domain.mesh().faceCount()), SessionOptions{});
  session.start();
  nlohmann::json reply;
  std::mutex m;
  std::condition_variable cv;
  bool got = false;
  const auto ask = [&](const std::string& text) {
    {
      std::lock_guard lock(m);
      got = false;
    }
    session.receive(text, [&](std::string r) {
      std::lock_guard lock(m);
      reply = nlohmann::json::parse(r);
      got = true;
      cv.notify_all();
    });
    std::unique_lock lock(m);
    cv.wait_for(lock, std::chrono::seconds(60), [&] { return got; });
    return reply;
  };
  EXPECT_EQ(ask(R"({"type":"source","face":5,"bary":[0.2,0.3,0.5]})")["type"], "ok");
  EXPECT_TRUE(session.waitSettled(60.0));
  const nlohmann::json values = ask(
      R"({"type":"probe","points":[{"face":5,"bary":[0.2,0.3,0.5]},{"face":100,"bary":[0.3,0.3,0.4]}]})")
      ["values"];
  ASSERT_EQ(values.size(), 2u);
  EXPECT_LT(std::abs(values[0].get<double>()), 0.05 * values[1].get<double>());
  EXPECT_GT(values[1].get<double>(), 0.0);
  const SharedBytes frame = session.latestFrame();
  EXPECT_EQ(decodeFrameHeader(*frame).format, FrameFormat::R16);
  session.stop();
}

}  // namespace
}  // namespace texgrad::viewer
