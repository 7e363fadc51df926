// Base URLs of a Keel server (`http[s]://host:port[/prefix]`) and query-string encoding.
#pragma once

#include <string>
#include <string_view>

namespace keel::client {

struct BaseUrl {
  bool tls = false;  // https
  std::string host;
  std::string port = "80";  // 443 for https unless given
  std::string path_prefix;  // "" or "/prefix" without a trailing '/'

  // "http[s]://host:port" + prefix, for messages.
  std::string origin() const;
  std::string scheme() const { return tls ? "https" : "http"; }
};

// Parses "http[s]://host[:port][/prefix]". Throws std::invalid_argument naming the URL and
// what is wrong.
BaseUrl parse_base_url(const std::string& url);

// Percent-encodes everything but RFC 3986 unreserved characters.
std::string url_encode(std::string_view text);

}  // namespace keel::client
