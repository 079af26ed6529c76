// Viewer module: who may talk to the server. Loopback binding needs no token; any other address
// requires a random token on every request (query parameter `token`).
#pragma once

#include <string>
#include <string_view>

namespace texgrad::viewer {

/// A fresh random token: 32 hexadecimal digits (128 bits from std::random_device).
std::string generateAccessToken();

/// True for "localhost", 127.0.0.0/8 and ::1 (the only addresses served without a token).
bool isLoopbackHost(std::string_view host);

/// Compares a presented token with the expected one in time independent of where they differ.
bool tokenMatches(std::string_view presented, std::string_view expected);

/// Value of query parameter `name` in a request target ("/path?a=1&b=2"), empty if absent.
std::string queryParameter(std::string_view target, std::string_view name);

/// Path part of a request target (before '?').
std::string_view targetPath(std::string_view target);

}  // namespace texgrad::viewer
