// ParallelForInOrder: every listed entry runs exactly once on any thread count, and the
// calls start in the listed order (exactly that order on one thread).
#include "core/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <mutex>
#include <vector>

namespace mebake {
namespace {

TEST(ParallelForInOrder, EachEntryOnceOnAnyThreadCount) {
    for (int threads : {1, 2, 4}) {
        ThreadLimit limit(threads);
        constexpr uint32_t kN = 1000;
        std::vector<uint32_t> order;
        for (uint32_t k = 0; k < kN; ++k)
            order.push_back((k * 7919u) % kN);  // a permutation (7919 is prime)
        std::vector<std::atomic<int>> runs(kN);
        ParallelForInOrder(order, [&](uint32_t c) { ++runs[c]; });
        for (uint32_t c = 0; c < kN; ++c)
            EXPECT_EQ(runs[c].load(), 1) << "entry " << c << ", " << threads << " threads";
    }
}

TEST(ParallelForInOrder, OneThreadFollowsTheOrder) {
    ThreadLimit limit(1);
    const std::vector<uint32_t> order = {5, 3, 9, 0, 1, 8, 2, 7, 6, 4};
    std::vector<uint32_t> seen;
    std::mutex mutex;
    ParallelForInOrder(order, [&](uint32_t c) {
        std::lock_guard lock(mutex);
        seen.push_back(c);
    });
    EXPECT_EQ(seen, order);
}

TEST(ParallelForInOrder, EmptyOrderCallsNothing) {
    int calls = 0;
    ParallelForInOrder({}, [&](uint32_t) { ++calls; });
    EXPECT_EQ(calls, 0);
}

}  // namespace
}  // namespace mebake
