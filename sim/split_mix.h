#pragma once
// SplitMix64's finaliser: a 64-bit hash of a counter, the same on every platform. The
// simulator's counter-based noise (sensor_noise, odometry) draws from it, so a draw depends only
// on its (seed, frame, stream) key, never on the order or thread that asks.
#include <cstdint>

namespace voxplan {

inline uint64_t SplitMix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace voxplan
