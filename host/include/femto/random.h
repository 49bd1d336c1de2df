// femto public API: PCG32 random numbers (O'Neill 2014) and hashing for seeding.
#pragma once

#include <cstdint>

namespace femto {

/// 64-bit mix (splitmix64 finaliser); used to derive independent streams from indices.
constexpr uint64_t mix64(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}
constexpr uint64_t hash_combine(uint64_t a, uint64_t b) {
    return mix64(a ^ (b + 0x9e3779b97f4a7c15ULL + (a << 6) + (a >> 2)));
}

class Pcg32 {
public:
    Pcg32() { seed(0x853c49e6748fea9bULL, 0xda3e39cb94b95bdbULL); }
    Pcg32(uint64_t state, uint64_t stream) { seed(state, stream); }
    void seed(uint64_t init_state, uint64_t stream) {
        state_ = 0;
        inc_ = (stream << 1u) | 1u;
        next_u32();
        state_ += init_state;
        next_u32();
    }
    uint32_t next_u32() {
        const uint64_t old = state_;
        state_ = old * 0x5851f42d4c957f2dULL + inc_;
        const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
        const uint32_t rot = static_cast<uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
    }
    /// Uniform in [0, 1), never 1.
    float next_float() { return static_cast<float>(next_u32() >> 8) * 0x1p-24f; }
    double next_double() {
        const uint64_t v = (static_cast<uint64_t>(next_u32()) << 32) | next_u32();
        return static_cast<double>(v >> 11) * 0x1p-53;
    }

private:
    uint64_t state_, inc_;
};

}  // namespace femto
