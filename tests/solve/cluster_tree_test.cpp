// The cluster tree over chart bounds (solve/cluster_tree.h): the same tree for the same
// charts, every chart in exactly one leaf, every node's sphere and chart range holding its
// children's.
#include "solve/cluster_tree.h"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

namespace mebake::solve {
namespace {

std::vector<ChartBound> RandomBounds(size_t n, uint64_t seed) {
    auto rnd = [&] {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        return float(double(seed >> 11) / double(1ull << 53));
    };
    std::vector<ChartBound> b(n);
    for (auto& c : b) {
        c.center = Vec3f(10 * rnd(), 3 * rnd(), 5 * rnd());
        c.radius = 0.5f * rnd();
        c.scale = 2 * c.radius;
    }
    // Ties: several charts at one centre must still give one order.
    for (size_t k = 0; k + 1 < n; k += 7)
        b[k + 1].center = b[k].center;
    return b;
}

TEST(ClusterTree, SameChartsSameTree) {
    const auto bounds = RandomBounds(500, 7);
    const ClusterTree a(bounds), b(bounds);
    ASSERT_EQ(a.nodes().size(), b.nodes().size());
    EXPECT_EQ(a.charts(), b.charts());
    for (size_t k = 0; k < a.nodes().size(); ++k) {
        const auto &x = a.nodes()[k], &y = b.nodes()[k];
        EXPECT_EQ(0, std::memcmp(&x.center, &y.center, sizeof(x.center)));
        EXPECT_EQ(x.radius, y.radius);
        EXPECT_EQ(x.first, y.first);
        EXPECT_EQ(x.count, y.count);
        EXPECT_EQ(x.child[0], y.child[0]);
        EXPECT_EQ(x.child[1], y.child[1]);
    }
}

TEST(ClusterTree, EveryChartInExactlyOneLeafAndNodesHoldTheirChildren) {
    for (size_t n : {1, 2, 3, 17, 500}) {
        const auto bounds = RandomBounds(n, 11 + n);
        const ClusterTree tree(bounds);
        const auto& nodes = tree.nodes();
        ASSERT_EQ(nodes.size(), 2 * n - 1);
        EXPECT_EQ(nodes[0].first, 0u);
        EXPECT_EQ(nodes[0].count, n);
        std::vector<int> in_leaf(n, 0);
        for (const auto& node : nodes) {
            if (node.leaf()) {
                ASSERT_EQ(node.count, 1u);
                const uint32_t c = tree.ChartsOf(node)[0];
                ++in_leaf[c];
                EXPECT_EQ(node.radius, bounds[c].radius);
                continue;
            }
            const auto& l = nodes[size_t(node.child[0])];
            const auto& r = nodes[size_t(node.child[1])];
            EXPECT_EQ(l.first, node.first);
            EXPECT_EQ(r.first, l.first + l.count);
            EXPECT_EQ(l.count + r.count, node.count);
            EXPECT_LE(int64_t(l.count) - int64_t(r.count), 1) << "median split";
            for (const auto* ch : {&l, &r}) {
                EXPECT_LE(Length(ch->center - node.center) + ch->radius, node.radius)
                    << "a node's sphere holds its children's";
                EXPECT_LE(ch->max_scale, node.max_scale);
            }
        }
        for (size_t c = 0; c < n; ++c)
            EXPECT_EQ(in_leaf[c], 1) << "chart " << c;
    }
}

TEST(ClusterTree, NoCharts) {
    const ClusterTree tree(std::vector<ChartBound>{});
    EXPECT_TRUE(tree.empty());
}

}  // namespace
}  // namespace mebake::solve
