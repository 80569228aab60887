// ChartField storage: the pending set exists only between the first pending() call and
// PushPending(), which pushes it to the leaves exactly as before; a values-only field (as
// read from a solution) holds no unshot set and still evaluates and subdivides.
#include "solve/field.h"

#include <gtest/gtest.h>

#include <cmath>

namespace mebake::solve {
namespace {

TEST(ChartField, PendingLivesOnlyDuringAGather) {
    ChartField f(0, 3);  // constants: Push and Pull keep a constant
    f.Subdivide(0);
    f.Subdivide(1);
    const size_t nodes = f.node_count();
    ASSERT_EQ(nodes, 9u);
    const size_t grown = f.MemoryBytes();
    f.Pull();  // the end of refinement trims the arrays' growth slack
    const size_t settled = f.MemoryBytes();
    EXPECT_LT(settled, grown);
    EXPECT_EQ(settled, nodes * (sizeof(QuadNode) + 2 * 3 * sizeof(float)));
    float* p = f.pending(0);
    p[0] = 1, p[1] = 2, p[2] = 3;
    f.pending(2)[1] = 10;
    EXPECT_GE(f.MemoryBytes(), settled + nodes * 3 * sizeof(float)) << "pending allocated";
    f.PushPending();
    EXPECT_EQ(f.MemoryBytes(), settled) << "pending freed";
    for (size_t n = 0; n < nodes; ++n) {
        if (!f.node(n).leaf())
            continue;
        const float extra = n == 2 ? 10.f : 0.f;
        EXPECT_EQ(f.value(n)[0], 1.f) << n;
        EXPECT_EQ(f.value(n)[1], 2.f + extra) << n;
        EXPECT_EQ(f.unshot(n)[2], 3.f) << n;
    }
    float out[3];
    f.EvalValue(0.9, 0.1, out);  // quadrant 1 = node 2
    EXPECT_EQ(out[1], 12.f);
    f.EvalUnshot(0.1, 0.9, out);
    EXPECT_EQ(out[1], 2.f);
    // A second gather allocates again and adds on top.
    f.pending(0)[0] = 1;
    f.PushPending();
    EXPECT_EQ(f.value(2)[0], 2.f);
    EXPECT_EQ(f.MemoryBytes(), settled);
}

// PushPending sums nested pending sets top-down (one sweep, each node's set restricted into
// its children's): the leaves get what pushing each set alone down its subtree gives, up to
// rounding. Order 2 (Push is not the identity), sets on the root, an interior node and a
// leaf at three depths, against one PushPending per set.
TEST(ChartField, NestedPendingSetsSumTopDownAsPushedOneByOne) {
    auto grow = [](ChartField* f) {
        f->Subdivide(0);          // 1..4
        f->Subdivide(2);          // 5..8
        f->Subdivide(6);          // 9..12
        f->Pull();
    };
    ChartField all(2, 3), one(2, 3);
    grow(&all);
    grow(&one);
    const int s = all.stride();
    auto set = [&](size_t n, int k) { return float((n + 1) * 0.37 + k * 0.11 - 0.9); };
    for (size_t n : {0u, 2u, 6u, 11u}) {
        for (int k = 0; k < s; ++k)
            all.pending(n)[k] = set(n, k);
        for (int k = 0; k < s; ++k)
            one.pending(n)[k] = set(n, k);
        one.PushPending();
    }
    all.PushPending();
    for (size_t n = 0; n < all.node_count(); ++n) {
        if (!all.node(n).leaf())
            continue;
        for (int k = 0; k < s; ++k) {
            EXPECT_NEAR(all.value(n)[k], one.value(n)[k], 1e-5 * (1 + std::abs(one.value(n)[k])))
                << n << " " << k;
            EXPECT_NEAR(all.unshot(n)[k], one.unshot(n)[k],
                        1e-5 * (1 + std::abs(one.unshot(n)[k])));
        }
    }
    float a[3], b[3];
    for (double u : {0.1, 0.55, 0.6, 0.9})
        for (double v : {0.2, 0.45, 0.7}) {
            all.EvalValue(u, v, a);
            one.EvalValue(u, v, b);
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(a[k], b[k], 1e-5 * (1 + std::abs(b[k])));
        }
}

TEST(ChartField, ValuesOnlyFieldEvaluatesAndSubdivides) {
    ChartField full(1, 3);
    full.Subdivide(0);
    for (size_t n = 0; n < full.node_count(); ++n)
        for (int k = 0; k < full.stride(); ++k)
            full.value(n)[k] = float(n * 10 + size_t(k));
    ChartField values(1, 3);
    values.Assign({full.nodes().begin(), full.nodes().end()},
                  {full.values().begin(), full.values().end()}, {});
    EXPECT_FALSE(values.has_unshot());
    EXPECT_TRUE(full.has_unshot());
    EXPECT_EQ(values.MemoryBytes(),
              values.node_count() * sizeof(QuadNode) + full.values().size() * sizeof(float));
    float a[3], b[3];
    for (double u : {0.1, 0.6})
        for (double v : {0.3, 0.8}) {
            full.EvalValue(u, v, a);
            values.EvalValue(u, v, b);
            for (int k = 0; k < 3; ++k)
                EXPECT_EQ(a[k], b[k]);
        }
    const int32_t first = values.Subdivide(1);
    EXPECT_EQ(values.node_count(), 9u);
    EXPECT_FALSE(values.has_unshot());
    values.pending(size_t(first))[0] = 5;
    values.PushPending();
    EXPECT_FALSE(values.has_unshot());
}

}  // namespace
}  // namespace mebake::solve
