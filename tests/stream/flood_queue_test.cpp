#include "stream/flood_queue.h"

#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <queue>
#include <random>
#include <tuple>
#include <vector>

namespace mebake::stream {
namespace {

using Key = std::tuple<float, uint32_t, uint32_t>;  // (cost, face, proxy), as the flood orders
using Reference = std::priority_queue<Key, std::vector<Key>, std::greater<Key>>;

// Pushes and pops interleaved like a flood (a pop, then a few pushes), from a small set
// of costs and faces so that equal costs, equal (cost, face) and exact duplicates occur,
// and pushes below the last pop.
TEST(FloodQueue, PopsInTheOrderOfAStdPriorityQueueTiesIncluded) {
    std::mt19937 rng(7);
    const float costs[] = {0.0f, 1e-30f, 0.25f, 0.5f, 0.5000001f, 3.0f, 1e30f,
                           std::numeric_limits<float>::infinity()};
    std::uniform_int_distribution<int> cost(0, 7), face(0, 40), proxy(0, 5), pushes(0, 4);
    FloodQueue queue;
    Reference reference;
    size_t pops = 0;
    for (int round = 0; round < 20000; ++round) {
        for (int k = pushes(rng); k > 0; --k) {
            const Key e{costs[cost(rng)], uint32_t(face(rng)), uint32_t(proxy(rng))};
            queue.push(std::get<0>(e), std::get<1>(e), std::get<2>(e));
            reference.push(e);
        }
        ASSERT_EQ(queue.size(), reference.size());
        if (reference.empty())
            continue;
        const FloodQueue::Entry e = queue.top();
        ASSERT_EQ(Key(e.cost, e.face, e.proxy), reference.top()) << "pop " << pops;
        ASSERT_EQ(queue.top_face(), e.face);
        queue.pop();
        reference.pop();
        ++pops;
        if (!reference.empty() && round % 2 == 0) {  // a peek before the next pushes, as
            ASSERT_EQ(queue.top_face(), std::get<1>(reference.top()));  // the flood's prefetch
        }
    }
    while (!reference.empty()) {
        const FloodQueue::Entry e = queue.top();
        ASSERT_EQ(Key(e.cost, e.face, e.proxy), reference.top());
        queue.pop();
        reference.pop();
    }
    EXPECT_TRUE(queue.empty());
    EXPECT_GT(pops, 10000u);
}

TEST(FloodQueue, FaceOrdersTiesOnCostAndProxyOrdersTiesOnFace) {
    FloodQueue queue;
    queue.push(2.0f, 1, 0);
    queue.push(1.0f, 9, 3);
    queue.push(1.0f, 9, 1);
    queue.push(1.0f, 4, 8);
    queue.push(0.0f, 100, 2);
    const std::vector<Key> want = {
        {0.0f, 100, 2}, {1.0f, 4, 8}, {1.0f, 9, 1}, {1.0f, 9, 3}, {2.0f, 1, 0}};
    for (const Key& k : want) {
        ASSERT_FALSE(queue.empty());
        const FloodQueue::Entry e = queue.top();
        EXPECT_EQ(Key(e.cost, e.face, e.proxy), k);
        queue.pop();
    }
    EXPECT_TRUE(queue.empty());
}

}  // namespace
}  // namespace mebake::stream
