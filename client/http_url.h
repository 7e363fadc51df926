// Base URLs of a Keel server (`http://host:port[/prefix]`) and query-string encoding.
#pragma once

#include <string>
#include <string_view>

namespace keel::client {

struct BaseUrl {
  std::string host;
  std::string port = "80";
  std::string path_prefix;  // "" or "/prefix" without a trailing '/'

  // "http://host:port" + prefix, for messages.
  std::string origin() const;
};

// Parses "http://host[:port][/prefix]". Throws std::invalid_argument naming the URL and
// what is wrong (only plain http is spoken; put TLS in front with a reverse proxy).
BaseUrl parse_base_url(const std::string& url);

// Percent-encodes everything but RFC 3986 unreserved characters.
std::string url_encode(std::string_view text);

}  // namespace keel::client
