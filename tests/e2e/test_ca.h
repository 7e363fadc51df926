// Certificate authorities for TLS tests, made with the openssl command: a CA and server
// certificates it signs for given names (EC P-256 keys, valid two days).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace keel::e2e {

struct TestCa {
  std::filesystem::path cert;  // PEM, to give clients as --ca-file
  std::filesystem::path key;
};

struct ServerCert {
  std::filesystem::path cert;  // PEM, the server's certificate
  std::filesystem::path key;
};

// Makes a self-signed CA named `name` in `dir`. Throws std::runtime_error with openssl's output.
TestCa make_test_ca(const std::filesystem::path& dir, const std::string& name);
// A server certificate signed by `ca` for `alt_names` ("DNS:localhost", "IP:127.0.0.1").
ServerCert make_server_cert(const TestCa& ca, const std::filesystem::path& dir, const std::string& name,
                            const std::vector<std::string>& alt_names);

}  // namespace keel::e2e
