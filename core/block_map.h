#pragma once
// BlockIndex -> pool slot. Open addressing with linear probing over packed 63-bit keys,
// load factor at most 1/2, backward-shift erase (no tombstones). Not thread-safe for writes;
// concurrent Find() is fine while nobody inserts.
#include <cstdint>
#include <utility>
#include <vector>

#include "core/index.h"

namespace voxplan {

class BlockMap {
 public:
  static constexpr uint32_t kNoSlot = ~0u;

  uint32_t Find(BlockIndex b) const;
  // Inserts b -> slot unless b is present; returns the slot stored and whether it was inserted.
  std::pair<uint32_t, bool> Insert(BlockIndex b, uint32_t slot);
  bool Erase(BlockIndex b);
  void Reserve(size_t n);
  void Clear();
  size_t size() const { return size_; }
  // Bytes of the table's arrays now, and at most while holding n entries (a table that grows
  // holds its old arrays beside the new ones until they are rehashed).
  size_t capacity_bytes() const { return keys_.size() * kBytesPerSlot; }
  size_t PeakBytesWith(size_t n) const;

  template <typename F>  // f(BlockIndex, slot), in table order (not sorted)
  void ForEach(F&& f) const {
    for (size_t i = 0; i < keys_.size(); ++i)
      if (keys_[i] != kEmpty) f(UnpackBlockIndex(keys_[i]), slots_[i]);
  }
  // (index, slot) pairs sorted by BlockIndex: the deterministic order for outputs.
  std::vector<std::pair<BlockIndex, uint32_t>> Sorted() const;

 private:
  static constexpr uint64_t kEmpty = ~0ull;
  static constexpr size_t kBytesPerSlot = sizeof(uint64_t) + sizeof(uint32_t);
  static uint64_t Hash(uint64_t k) {  // splitmix64 finaliser
    k ^= k >> 30;
    k *= 0xbf58476d1ce4e5b9ull;
    k ^= k >> 27;
    k *= 0x94d049bb133111ebull;
    return k ^ (k >> 31);
  }
  void Rehash(size_t capacity);

  std::vector<uint64_t> keys_;
  std::vector<uint32_t> slots_;
  size_t size_ = 0;
  size_t mask_ = 0;
};

}  // namespace voxplan
