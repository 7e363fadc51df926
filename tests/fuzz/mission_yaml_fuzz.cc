// mission.yaml (worker/io/mission.h): any text is read into a manifest or refused with an
// error naming mission.yaml and the field (IoError / ContractError).
#include <stdexcept>

#include "tests/fuzz/fuzz_util.h"
#include "worker/io/mission.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto dir = keel::fuzz::scratch() / "mission";
  std::filesystem::create_directories(dir);
  const auto file = keel::fuzz::write_input("mission/mission.yaml", data, size);
  try {
    (void)keel::io::load_mission(dir);
  } catch (const std::runtime_error&) {  // IoError, ContractError: both name the file
  }
  return 0;
}
