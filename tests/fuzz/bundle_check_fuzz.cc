// The server's mission bundle check (server/bundle_check.h): any upload is accepted as a
// safe tar or refused with a BundleError naming the member.
#include "server/bundle_check.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto file = keel::fuzz::write_input("bundle.tar", data, size);
  try {
    (void)keel::server::check_mission_bundle(file);
  } catch (const keel::server::BundleError&) {
  }
  return 0;
}
