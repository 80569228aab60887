// ChartField storage: the pending set exists only between the first pending() call and
// PushPending(), which pushes it to the leaves exactly as before; a values-only field (as
// read from a solution) holds no unshot set and still evaluates and subdivides; a gather's
// PushPending recomputes only the interior nodes above changed leaves, with the bits of a
// whole Pull.
#include "solve/field.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

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

// Gathers that light a few nodes (the root now and then), with ClearUnshot and Subdivide
// between them: after every PushPending the field holds exactly what a whole Pull gives.
TEST(ChartField, PushPendingPullsAboveChangedLeavesAsAWholePull) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> val(-1.f, 1.f);
    ChartField f(2, 9);
    for (int k = 0; k < 40; ++k) {
        size_t n = rng() % f.node_count();
        while (!f.node(n).leaf())
            n = size_t(f.node(n).first_child) + rng() % 4;
        if (f.node(n).level < 6)
            f.Subdivide(n);
    }
    for (size_t n = 0; n < f.node_count(); ++n)
        for (int k = 0; k < f.stride(); ++k)
            f.value(n)[k] = f.unshot(n)[k] = val(rng);
    f.Pull();
    auto same_bits = [](std::span<const float> a, std::span<const float> b) {
        return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
    };
    int partial = 0;
    for (int gather = 0; gather < 60; ++gather) {
        if (gather % 7 == 3)
            f.ClearUnshot();
        if (gather % 11 == 5) {
            size_t n = rng() % f.node_count();
            while (!f.node(n).leaf())
                n = size_t(f.node(n).first_child) + rng() % 4;
            f.Subdivide(n);
        }
        const int lit = gather % 13 == 0 ? 1 : 1 + int(rng() % 3);
        for (int l = 0; l < lit; ++l) {
            const size_t n = gather % 13 == 0 ? 0 : 1 + rng() % (f.node_count() - 1);
            for (int k = 0; k < f.stride(); ++k)
                f.pending(n)[k] += val(rng);
        }
        if (f.pulled())
            ++partial;  // the gather recomputes only the nodes above its lit leaves
        f.PushPending();
        EXPECT_TRUE(f.pulled());
        ChartField whole(f);
        whole.Pull();
        ASSERT_TRUE(same_bits(f.values(), whole.values())) << gather;
        ASSERT_TRUE(same_bits(f.unshots(), whole.unshots())) << gather;
    }
    EXPECT_GE(partial, 50);  // all but the gathers after a Subdivide (and the first)
}

}  // namespace
}  // namespace mebake::solve
