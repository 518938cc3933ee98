#pragma once
// Whether libtom's vector paths may run: besides the CPU check each path makes, the environment
// variable TOM_SIMD=0 turns them all off (read once), so the scalar paths, the ones CPUs without
// AVX take, can be tested and compared on any machine.

#include <cstdlib>
#include <cstring>

namespace tom::detail {

inline bool simd_enabled() noexcept {
    static const bool enabled = [] {
        const char* value = std::getenv("TOM_SIMD");
        return !(value && std::strcmp(value, "0") == 0);
    }();
    return enabled;
}

} // namespace tom::detail
