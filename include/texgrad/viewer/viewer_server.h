// Viewer module: the HTTP + WebSocket server of `texgrad view` (Boost.Beast, one I/O thread).
// Serves only its own page, the loaded mesh and the session's frames; validates every request.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "texgrad/apps/texel_domain.h"
#include "texgrad/viewer/viewer_session.h"

namespace texgrad::viewer {

/// Where and what the server serves.
struct ServerOptions {
  /// Address to bind: an IP literal or "localhost". Anything but loopback requires the token.
  std::string host = "127.0.0.1";
  /// TCP port; 0 picks a free one (see ViewerServer::port()).
  uint16_t port = 8080;
  /// Folder with the built page (index.html, viewer.js): viewer/dist after scripts/build-viewer.sh.
  std::filesystem::path webRoot;
  /// Most WebSocket connections served at once; further upgrades are refused (503).
  int maxConnections = 16;
  /// Throws InvalidInputError naming the first bad field.
  void validate() const;
};

/// Binary mesh payload of GET /api/mesh (little-endian): "TGM1", faces F, positions V, 0; then
/// u32 triangles[3F], f32 positions[3V], f32 per-corner uvs[6F].
std::vector<uint8_t> encodeMesh(const TexturedMesh& mesh);

/// The server. Routes: / (page), /viewer.js, /api/info (JSON), /api/mesh, /ws (WebSocket).
class ViewerServer {
 public:
  /// Loads the page from options.webRoot and binds; throws IoError if the page is missing or
  /// the address cannot be bound. `session` and `domain` must outlive the server.
  ViewerServer(ViewerSession& session, const TexelDomain& domain, const ServerOptions& options);
  ~ViewerServer();
  ViewerServer(const ViewerServer&) = delete;
  ViewerServer& operator=(const ViewerServer&) = delete;

  /// Bound port.
  uint16_t port() const;
  /// Access token every request must carry (`?token=`), empty when bound to loopback.
  const std::string& token() const;
  /// URL to open (with the token when one is required).
  std::string url() const;
  /// Serves until stop() or SIGINT/SIGTERM.
  void run();
  /// Makes run() return; callable from any thread.
  void stop();

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;
};

}  // namespace texgrad::viewer
