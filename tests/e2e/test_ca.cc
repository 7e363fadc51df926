#include "tests/e2e/test_ca.h"

#include <fstream>
#include <stdexcept>

#include "tests/e2e/process.h"

namespace keel::e2e {

namespace fs = std::filesystem;

namespace {

void openssl(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {"openssl"};
  argv.insert(argv.end(), args.begin(), args.end());
  const RunResult result = run_command(argv, std::chrono::seconds(60));
  if (result.exit_code != 0)
    throw std::runtime_error("openssl " + args.front() + " failed: " + result.output);
}

}  // namespace

TestCa make_test_ca(const fs::path& dir, const std::string& name) {
  fs::create_directories(dir);
  TestCa ca{dir / (name + ".pem"), dir / (name + ".key")};
  openssl({"req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes",
           "-keyout", ca.key.string(), "-out", ca.cert.string(), "-days", "2", "-subj",
           "/CN=" + name, "-addext", "basicConstraints=critical,CA:TRUE", "-addext",
           "keyUsage=critical,keyCertSign,cRLSign"});
  return ca;
}

ServerCert make_server_cert(const TestCa& ca, const fs::path& dir, const std::string& name,
                            const std::vector<std::string>& alt_names) {
  fs::create_directories(dir);
  ServerCert out{dir / (name + ".pem"), dir / (name + ".key")};
  const fs::path request = dir / (name + ".csr");
  const fs::path extensions = dir / (name + ".ext");
  std::string names;
  for (const auto& alt : alt_names) names += (names.empty() ? "" : ",") + alt;
  std::ofstream(extensions) << "subjectAltName=" << names
                            << "\nbasicConstraints=CA:FALSE\nextendedKeyUsage=serverAuth\n";
  openssl({"req", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes", "-keyout",
           out.key.string(), "-out", request.string(), "-subj", "/CN=" + name});
  openssl({"x509", "-req", "-in", request.string(), "-CA", ca.cert.string(), "-CAkey",
           ca.key.string(), "-CAcreateserial", "-out", out.cert.string(), "-days", "2", "-extfile",
           extensions.string()});
  return out;
}

}  // namespace keel::e2e
