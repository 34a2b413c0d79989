// ProduceAhead (core/parallel.h): items consumed in order on the calling thread, each produced
// once, never more than `ahead` items ahead of the one consumed, an early stop and exceptions.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/parallel.h"

namespace voxplan {
namespace {

// Runs ProduceAhead over n items, checking the contract as it goes.
struct AheadRun {
  size_t n, ahead;
  size_t stop_after = SIZE_MAX;  // consume returns false at this item
  std::vector<std::atomic<int>> produced;
  std::vector<size_t> consumed;
  std::atomic<size_t> max_lead{0};  // produce(i) started with consumed.size() items done
  std::atomic<size_t> done{0};
  bool consumed_off_thread = false;

  AheadRun(size_t items, size_t lead) : n(items), ahead(lead), produced(items) {}

  void Go() {
    const std::thread::id caller = std::this_thread::get_id();
    ProduceAhead(
        n, ahead,
        [&](size_t i) {
          const size_t lead = i - done.load();
          size_t seen = max_lead.load();
          while (lead > seen && !max_lead.compare_exchange_weak(seen, lead)) {
          }
          // Uneven work, so that workers and the caller overtake each other.
          std::this_thread::sleep_for(std::chrono::microseconds(i % 3 == 0 ? 300 : 20));
          produced[i]++;
        },
        [&](size_t i) {
          if (std::this_thread::get_id() != caller) consumed_off_thread = true;
          EXPECT_EQ(produced[i].load(), 1) << "item " << i << " consumed before it was made";
          consumed.push_back(i);
          done.store(consumed.size());
          return i != stop_after;
        });
  }
};

TEST(ProduceAhead, ConsumesEveryItemInOrderOnTheCallingThreadAfterMakingItOnce) {
  for (int threads : {1, 2, 4}) {
    ThreadLimit limit(threads);
    for (size_t ahead : {0, 1, 3, 8}) {
      AheadRun run(40, ahead);
      run.Go();
      ASSERT_EQ(run.consumed.size(), 40u) << threads << " threads, ahead " << ahead;
      for (size_t i = 0; i < 40; ++i) {
        EXPECT_EQ(run.consumed[i], i);
        EXPECT_EQ(run.produced[i].load(), 1) << "item " << i;
      }
      EXPECT_FALSE(run.consumed_off_thread);
      // Item i is started only once item i - ahead - 1 has been consumed.
      EXPECT_LE(run.max_lead.load(), ahead) << threads << " threads, ahead " << ahead;
    }
  }
}

TEST(ProduceAhead, AFalseFromConsumeStopsEverything) {
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    AheadRun run(50, 4);
    run.stop_after = 10;
    run.Go();
    ASSERT_EQ(run.consumed.size(), 11u);
    EXPECT_EQ(run.consumed.back(), 10u);
    // Nothing beyond the items already ahead of the stop was made.
    for (size_t i = 15; i < 50; ++i) EXPECT_EQ(run.produced[i].load(), 0) << "item " << i;
  }
}

TEST(ProduceAhead, ExceptionsReachTheCallerAfterTheWorkersAreDone) {
  ThreadLimit limit(2);
  std::atomic<int> running{0};
  std::vector<size_t> consumed;
  EXPECT_THROW(ProduceAhead(
                   30, 3,
                   [&](size_t i) {
                     running++;
                     std::this_thread::sleep_for(std::chrono::microseconds(200));
                     running--;
                     if (i == 7) throw std::runtime_error("item 7");
                   },
                   [&](size_t i) {
                     consumed.push_back(i);
                     return true;
                   }),
               std::runtime_error);
  EXPECT_EQ(running.load(), 0);    // no produce call outlives ProduceAhead
  EXPECT_EQ(consumed.size(), 7u);  // items 0..6: item 7's error stops before it is consumed
  EXPECT_THROW(ProduceAhead(
                   30, 3, [](size_t) {},
                   [](size_t i) -> bool {
                     if (i == 2) throw std::runtime_error("consume 2");
                     return true;
                   }),
               std::runtime_error);
}

TEST(ProduceAhead, NoItemsCallsNothing) {
  bool called = false;
  ProduceAhead(
      0, 3, [&](size_t) { called = true; },
      [&](size_t) {
        called = true;
        return true;
      });
  EXPECT_FALSE(called);
}

}  // namespace
}  // namespace voxplan
