// Exit codes of `keel`, for scripts (documented in `keel --help` and docs/cli.md).
#pragma once

namespace keel::client {

class ApiCallError;

enum ExitCode : int {
  kExitOk = 0,
  kExitUsage = 1,        // bad flags or arguments
  kExitRefused = 2,      // the server refused the request (4xx)
  kExitUnreachable = 3,  // server unreachable, transport failure, 5xx, malformed answer
  kExitJobFailed = 4,    // the watched job failed
  kExitJobCanceled = 5,  // the watched job was canceled
  kExitLocalFile = 6,    // local file error (missing mission folder, unreadable file)
};

// 4xx → kExitRefused; transport (status 0), 5xx and anything else → kExitUnreachable.
int exit_code_for(const ApiCallError& error);

// The exit-code table as printed in the `keel --help` footer.
const char* exit_code_help();

}  // namespace keel::client
