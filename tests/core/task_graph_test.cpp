// TaskGraph: every node runs once, after all of its predecessors, on any thread count;
// an exception stops the graph and is rethrown.
#include "core/task_graph.h"

#include "core/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

namespace mebake {
namespace {

TEST(TaskGraph, NodesRunOnceAfterTheirPredecessors) {
    for (int threads : {1, 2, 4}) {
        ThreadLimit limit(threads);
        // A lattice: node (i, j) after (i - 1, j) and (i, j - 1); each records the order
        // stamp it ran at, which must exceed its predecessors'.
        constexpr int kN = 30;
        std::atomic<int> clock{0};
        std::vector<int> stamp(kN * kN, -1);
        TaskGraph graph;
        for (int i = 0; i < kN; ++i)
            for (int j = 0; j < kN; ++j)
                graph.Add([&stamp, &clock, i, j] {
                    EXPECT_EQ(stamp[size_t(i * kN + j)], -1) << "ran twice";
                    if (i > 0) {
                        EXPECT_GE(stamp[size_t((i - 1) * kN + j)], 0);
                    }
                    if (j > 0) {
                        EXPECT_GE(stamp[size_t(i * kN + j - 1)], 0);
                    }
                    stamp[size_t(i * kN + j)] = clock++;
                });
        for (int i = 0; i < kN; ++i)
            for (int j = 0; j < kN; ++j) {
                if (i > 0)
                    graph.Precede(TaskGraph::Node((i - 1) * kN + j), TaskGraph::Node(i * kN + j));
                if (j > 0)
                    graph.Precede(TaskGraph::Node(i * kN + j - 1), TaskGraph::Node(i * kN + j));
            }
        graph.Run();
        for (int s : stamp)
            EXPECT_GE(s, 0) << "every node ran";
        EXPECT_EQ(clock.load(), kN * kN);
    }
}

TEST(TaskGraph, AnExceptionStopsTheGraphAndIsRethrown) {
    std::atomic<int> after{0};
    TaskGraph graph;
    const auto a = graph.Add([] { throw std::runtime_error("node a"); });
    const auto b = graph.Add([&after] { ++after; });
    graph.Precede(a, b);
    try {
        graph.Run();
        FAIL() << "no exception";
    } catch (const std::runtime_error& e) {
        EXPECT_STREQ(e.what(), "node a");
    }
    EXPECT_EQ(after.load(), 0) << "a successor of the failed node never starts";
}

}  // namespace
}  // namespace mebake
