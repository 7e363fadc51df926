// Random identifiers: a kind prefix and hex digits from OpenSSL's CSPRNG, so ids are
// unguessable and never collide in practice (64 bits for 16 hex digits).
#pragma once

#include <cstddef>
#include <string>

namespace keel::storage {

// Prefixes of the ids the store hands out.
inline constexpr const char* kMissionPrefix = "m_";
inline constexpr const char* kJobPrefix = "j_";
inline constexpr const char* kUploadPrefix = "u_";
inline constexpr const char* kArtifactPrefix = "a_";
inline constexpr const char* kLeasePrefix = "l_";
inline constexpr const char* kTokenPrefix = "t_";
inline constexpr const char* kBatchPrefix = "b_";

// `bytes` random bytes as 2*bytes lowercase hex digits. Throws if the RNG fails.
std::string random_hex(size_t bytes);
// prefix + 16 random hex digits, e.g. "j_3f9a0c1e7b2d4a65".
std::string new_id(const std::string& prefix);

}  // namespace keel::storage
