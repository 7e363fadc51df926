// Every JSON contract of the API and the worker protocol (proto/): any document either
// reads into the struct or is refused with a ContractError naming the field.
#include <nlohmann/json.hpp>

#include "tests/fuzz/fuzz_util.h"
#include "tests/fuzz/json_contracts.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto input = keel::fuzz::split_selector(data, size);
  const nlohmann::json body = nlohmann::json::parse(input.data, input.data + input.size, nullptr,
                                                    /*allow_exceptions=*/false);
  if (body.is_discarded()) return 0;
  (void)keel::fuzz::read_contract(input.selector % keel::fuzz::kContracts, body);
  return 0;
}
