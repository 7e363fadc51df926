#include "server/token_admin.h"

#include <cctype>
#include <limits>
#include <stdexcept>

#include "server/data_dir.h"

namespace keel::server {

IssuedToken issue_token(storage::Store& store, const proto::TokenRequest& request, int64_t now_ms) {
  storage::TokenSpec spec;
  spec.label = request.label;
  spec.role = request.role;
  spec.project = request.project;
  spec.expires_at_ms = request.expires_in_s > 0 ? now_ms + request.expires_in_s * 1000 : 0;
  IssuedToken issued;
  issued.token = random_token();
  issued.info = store.add_token(issued.token, spec);
  return issued;
}

int64_t parse_duration_seconds(const std::string& text) {
  if (text == "never") return 0;
  auto fail = [&] {
    return std::invalid_argument("duration '" + text +
                                 "': expected a number with an optional unit s, m, h, d or w "
                                 "(e.g. 30d), or 'never'");
  };
  if (text.empty() || !std::isdigit(static_cast<unsigned char>(text[0]))) throw fail();
  size_t digits = 0;
  while (digits < text.size() && std::isdigit(static_cast<unsigned char>(text[digits]))) ++digits;
  if (digits > 12) throw fail();  // keeps the product below int64's range
  const int64_t count = std::stoll(text.substr(0, digits));
  const std::string unit = text.substr(digits);
  int64_t scale = 0;
  if (unit.empty() || unit == "s")
    scale = 1;
  else if (unit == "m")
    scale = 60;
  else if (unit == "h")
    scale = 3600;
  else if (unit == "d")
    scale = 86400;
  else if (unit == "w")
    scale = 7 * 86400;
  else
    throw fail();
  return count * scale;
}

}  // namespace keel::server
