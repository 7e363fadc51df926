// Seeds for fuzz_json_contracts: a valid document of every contract (json_contracts.h), as
// the server, client and workers send them, prefixed by the contract's selector. Without them
// the corpus held no document any contract accepted (an hour of fuzzing read none): libFuzzer
// fuzzed nlohmann's parser and the refusals, never a contract's reading of a valid document
// nor its round trip through to_json. Each is read back before it is written: a document the
// contract refuses is an error (fuzz_seeds fails).
#pragma once

#include <filesystem>

namespace keel::fuzz {

int write_contract_seeds(const std::filesystem::path& dir);

}  // namespace keel::fuzz
