#include "core/block_map.h"

#include <algorithm>
#include <bit>

#include "core/assert.h"

namespace voxplan {

uint32_t BlockMap::Find(BlockIndex b) const {
  if (size_ == 0) return kNoSlot;
  const uint64_t key = PackBlockIndex(b);
  for (size_t i = Hash(key) & mask_;; i = (i + 1) & mask_) {
    if (keys_[i] == key) return slots_[i];
    if (keys_[i] == kEmpty) return kNoSlot;
  }
}

std::pair<uint32_t, bool> BlockMap::Insert(BlockIndex b, uint32_t slot) {
  VOXPLAN_ASSERT(InPackRange(b));
  if ((size_ + 1) * 2 > keys_.size()) Rehash(std::max<size_t>(64, keys_.size() * 2));
  const uint64_t key = PackBlockIndex(b);
  size_t i = Hash(key) & mask_;
  for (; keys_[i] != kEmpty; i = (i + 1) & mask_)
    if (keys_[i] == key) return {slots_[i], false};
  keys_[i] = key;
  slots_[i] = slot;
  ++size_;
  return {slot, true};
}

bool BlockMap::Erase(BlockIndex b) {
  if (size_ == 0) return false;
  const uint64_t key = PackBlockIndex(b);
  size_t i = Hash(key) & mask_;
  while (keys_[i] != key) {
    if (keys_[i] == kEmpty) return false;
    i = (i + 1) & mask_;
  }
  // Backward shift: move later entries of the probe run into the hole when allowed.
  for (size_t j = (i + 1) & mask_; keys_[j] != kEmpty; j = (j + 1) & mask_) {
    const size_t home = Hash(keys_[j]) & mask_;
    // Entry j may move to i if its home is not cyclically in (i, j].
    const bool movable = (j > i) ? (home <= i || home > j) : (home <= i && home > j);
    if (movable) {
      keys_[i] = keys_[j];
      slots_[i] = slots_[j];
      i = j;
    }
  }
  keys_[i] = kEmpty;
  --size_;
  return true;
}

void BlockMap::Reserve(size_t n) {
  const size_t want = std::bit_ceil(std::max<size_t>(64, n * 2));
  if (want > keys_.size()) Rehash(want);
}

size_t BlockMap::PeakBytesWith(size_t n) const {
  size_t capacity = keys_.size();
  if (n * 2 <= capacity) return capacity_bytes();
  while (n * 2 > capacity) capacity = std::max<size_t>(64, capacity * 2);
  return (capacity + capacity / 2) * kBytesPerSlot;  // the new arrays beside the old
}

void BlockMap::Clear() {
  keys_.clear();
  slots_.clear();
  size_ = 0;
  mask_ = 0;
}

void BlockMap::Rehash(size_t capacity) {
  std::vector<uint64_t> old_keys(capacity, kEmpty);
  std::vector<uint32_t> old_slots(capacity, kNoSlot);
  old_keys.swap(keys_);
  old_slots.swap(slots_);
  mask_ = capacity - 1;
  for (size_t k = 0; k < old_keys.size(); ++k) {
    if (old_keys[k] == kEmpty) continue;
    size_t i = Hash(old_keys[k]) & mask_;
    while (keys_[i] != kEmpty) i = (i + 1) & mask_;
    keys_[i] = old_keys[k];
    slots_[i] = old_slots[k];
  }
}

std::vector<std::pair<BlockIndex, uint32_t>> BlockMap::Sorted() const {
  std::vector<std::pair<BlockIndex, uint32_t>> out;
  out.reserve(size_);
  ForEach([&](BlockIndex b, uint32_t s) { out.emplace_back(b, s); });
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

}  // namespace voxplan
