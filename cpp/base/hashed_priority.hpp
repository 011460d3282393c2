// The priority of the hashed colouring: splitmix64 of a node's number (its global id in the
// distributed solver, the serial hierarchy's node number), ties -- which a 64-bit hash makes rare --
// by the number. The greedy colouring that visits the nodes from the highest priority down gives the
// same colours on one rank as the distributed Jones-Plassmann colouring on any number of ranks
// (python/contactmg/distributed/colouring.py computes the same priority with numpy).
#pragma once
#include <cstdint>
#include "base/common.hpp"

namespace cmg {

inline std::uint64_t splitmix64(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

inline std::uint64_t hashed_priority(Index number) { return splitmix64((std::uint64_t)number); }

// Whether node number a comes before node number b in the hashed order (higher priority first).
inline bool hashed_before(Index a, Index b) {
  const std::uint64_t pa = hashed_priority(a), pb = hashed_priority(b);
  return pa != pb ? pa > pb : a > b;
}

}  // namespace cmg
