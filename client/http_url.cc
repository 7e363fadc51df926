#include "client/http_url.h"

#include <cctype>
#include <stdexcept>

namespace keel::client {

std::string BaseUrl::origin() const {
  return scheme() + "://" + host + ":" + port + path_prefix;
}

BaseUrl parse_base_url(const std::string& url) {
  auto fail = [&](const std::string& why) {
    throw std::invalid_argument("server URL '" + url + "': " + why);
  };
  BaseUrl out;
  std::string rest;
  if (url.compare(0, 7, "http://") == 0) {
    rest = url.substr(7);
  } else if (url.compare(0, 8, "https://") == 0) {
    rest = url.substr(8);
    out.tls = true;
    out.port = "443";
  } else {
    fail("expected http://host:port or https://host:port");
  }
  const size_t slash = rest.find('/');
  if (slash != std::string::npos) {
    out.path_prefix = rest.substr(slash);
    rest.resize(slash);
    while (!out.path_prefix.empty() && out.path_prefix.back() == '/') out.path_prefix.pop_back();
  }
  if (rest.find('@') != std::string::npos)
    fail("credentials in the URL are not supported; use a token");
  std::string host = rest;
  if (!rest.empty() && rest.front() == '[') {  // [IPv6]:port
    const size_t close = rest.find(']');
    if (close == std::string::npos) fail("unterminated '[' in the host");
    host = rest.substr(1, close - 1);
    if (close + 1 < rest.size()) {
      if (rest[close + 1] != ':') fail("expected ':' after ']'");
      out.port = rest.substr(close + 2);
    }
  } else if (const size_t colon = rest.rfind(':'); colon != std::string::npos) {
    host = rest.substr(0, colon);
    out.port = rest.substr(colon + 1);
  }
  if (host.empty()) fail("missing host");
  if (out.port.empty()) fail("empty port");
  for (char c : out.port)
    if (!std::isdigit(static_cast<unsigned char>(c)))
      fail("port '" + out.port + "' is not a number");
  const long port = std::stol(out.port);
  if (port < 1 || port > 65535) fail("port " + out.port + " outside 1..65535");
  out.host = host;
  return out;
}

std::string url_encode(std::string_view text) {
  static const char* kHex = "0123456789ABCDEF";
  std::string out;
  out.reserve(text.size());
  for (unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') {
      out += static_cast<char>(c);
    } else {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

}  // namespace keel::client
