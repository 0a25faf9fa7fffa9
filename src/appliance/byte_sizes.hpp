#pragma once
// The configuration gives disk sizes in MiB ([store] min_free_mb, [recorder] quota_mb); the store
// and the recorder count bytes.
#include <cstdint>

namespace epa::appliance {

inline std::uint64_t mib_to_bytes(double mib) { return static_cast<std::uint64_t>(mib * 1024 * 1024); }

}  // namespace epa::appliance
