// Viewer module: access tokens, loopback detection and request-target parsing.
#include "texgrad/viewer/access_token.h"

#include <boost/asio/ip/address.hpp>
#include <random>

namespace texgrad::viewer {

std::string generateAccessToken() {
  std::random_device device;
  static constexpr char kHex[] = "0123456789abcdef";
  std::string token;
  for (int i = 0; i < 4; ++i) {
    const uint32_t word = device();
    for (int k = 0; k < 8; ++k) token.push_back(kHex[(word >> (4 * k)) & 0xFu]);
  }
  return token;
}

bool isLoopbackHost(std::string_view host) {
  if (host == "localhost") return true;
  boost::system::error_code ec;
  const auto address = boost::asio::ip::make_address(std::string(host), ec);
  return !ec && address.is_loopback();
}

bool tokenMatches(std::string_view presented, std::string_view expected) {
  if (expected.empty()) return true;
  unsigned char diff = presented.size() == expected.size() ? 0 : 1;
  for (size_t i = 0; i < expected.size(); ++i)
    diff |= static_cast<unsigned char>(expected[i] ^ (i < presented.size() ? presented[i] : 0));
  return diff == 0;
}

std::string queryParameter(std::string_view target, std::string_view name) {
  const size_t q = target.find('?');
  if (q == std::string_view::npos) return {};
  std::string_view query = target.substr(q + 1);
  while (!query.empty()) {
    const size_t amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    const size_t eq = pair.find('=');
    if (pair.substr(0, eq) == name && eq != std::string_view::npos)
      return std::string(pair.substr(eq + 1));
    if (amp == std::string_view::npos) break;
    query.remove_prefix(amp + 1);
  }
  return {};
}

std::string_view targetPath(std::string_view target) {
  return target.substr(0, target.find('?'));
}

}  // namespace texgrad::viewer
