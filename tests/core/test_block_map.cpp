#include <gtest/gtest.h>

#include <map>
#include <random>

#include "core/block_map.h"
#include "core/block_pool.h"

namespace voxplan {
namespace {

TEST(BlockMap, AgreesWithStdMapUnderRandomInsertEraseFind) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coord(-6, 6);
  BlockMap map;
  std::map<BlockIndex, uint32_t> reference;
  for (int step = 0; step < 20000; ++step) {
    const BlockIndex b{coord(rng), coord(rng), coord(rng)};
    switch (rng() % 3) {
      case 0: {
        const auto [slot, inserted] = map.Insert(b, uint32_t(step));
        const auto [it, ref_inserted] = reference.emplace(b, uint32_t(step));
        EXPECT_EQ(inserted, ref_inserted);
        EXPECT_EQ(slot, it->second);
        break;
      }
      case 1:
        EXPECT_EQ(map.Erase(b), reference.erase(b) == 1);
        break;
      default: {
        const auto it = reference.find(b);
        EXPECT_EQ(map.Find(b), it == reference.end() ? BlockMap::kNoSlot : it->second);
      }
    }
    ASSERT_EQ(map.size(), reference.size());
  }
  // Sorted() is the deterministic output order and matches the reference exactly.
  const auto sorted = map.Sorted();
  ASSERT_EQ(sorted.size(), reference.size());
  size_t i = 0;
  for (const auto& [b, s] : reference) {
    EXPECT_EQ(sorted[i].first, b);
    EXPECT_EQ(sorted[i].second, s);
    ++i;
  }
}

TEST(BlockMap, ReserveKeepsEntries) {
  BlockMap map;
  for (int i = 0; i < 100; ++i) map.Insert({i, -i, i / 2}, uint32_t(i));
  map.Reserve(100000);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(map.Find({i, -i, i / 2}), uint32_t(i));
}

TEST(BlockPool, AddressesAreStableAndSlotsReused) {
  BlockPool pool;
  const uint32_t first = pool.Allocate();
  TsdfBlock* address = &pool[first];
  address->weight[3] = 42;
  for (int i = 0; i < 3000; ++i) pool.Allocate();  // grows by many chunks
  EXPECT_EQ(&pool[first], address);
  EXPECT_EQ(pool[first].weight[3], 42);
  pool.Release(first);
  const uint32_t again = pool.Allocate();
  EXPECT_EQ(again, first);
  EXPECT_EQ(pool[again].weight[3], 0) << "a reused slot must come back reset";
  EXPECT_EQ(pool[again].tsdf[0], int16_t(kTsdfScale));
}

}  // namespace
}  // namespace voxplan
