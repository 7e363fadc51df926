#include "client/exit_codes.h"

#include "client/api_client.h"

namespace keel::client {

int exit_code_for(const ApiCallError& error) {
  if (error.status() >= 400 && error.status() < 500) return kExitRefused;
  return kExitUnreachable;
}

const char* exit_code_help() {
  return "Exit codes:\n"
         "  0  success\n"
         "  1  usage error\n"
         "  2  the server refused the request (4xx)\n"
         "  3  server unreachable, transport failure or server error (5xx)\n"
         "  4  the watched job failed\n"
         "  5  the watched job was canceled\n"
         "  6  local file error (missing mission folder, unreadable file)\n"
         "\n"
         "Server and token: --url/--token > KEEL_URL, KEEL_TOKEN, KEEL_TOKEN_FILE >\n"
         "~/.config/keel/config.yaml (url:, token:, token_file:). -v says which was used.";
}

}  // namespace keel::client
