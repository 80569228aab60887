// ContinuousField::Eval's one-leaf shortcut (one descent where the box around a point lies
// in its centre's leaf) gives the bits of the definition it replaced: the leaves at the
// box's four corners, the centre's own fit when they are one leaf, else the blend. Points
// on node borders, a box half-width either side of them and a few ulps off, at 0 and 1,
// and at random, on an uneven tree whose leaves all have their own fit. The points run along
// rows, so most reuse the thread's last leaf (CentreLeaf); the second test mixes fields and
// orders so the last leaf is stale, another field's or a neighbour's.
#include "output/continuous_field.h"

#include "solve/basis.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <utility>
#include <vector>

namespace mebake::output {
namespace {

// The definition before the shortcut (continuous_field.cpp at 64d1203).
void Reference(const solve::ChartField& f, double delta, double u, double v, float* out) {
    const double u0 = std::max(0.0, u - delta), u1 = std::min(1.0, u + delta);
    const double v0 = std::max(0.0, v - delta), v1 = std::min(1.0, v + delta);
    std::vector<size_t> leaves;
    for (const double cv : {v0, v1})
        for (const double cu : {u0, u1}) {
            double s, t;
            const size_t n = f.LeafAt(cu, cv, &s, &t);
            if (std::find(leaves.begin(), leaves.end(), n) == leaves.end())
                leaves.push_back(n);
        }
    if (leaves.size() == 1) {
        f.EvalValue(u, v, out);
        return;
    }
    std::fill(out, out + f.blocks(), 0.f);
    double total = 0;
    float part[9];
    for (const size_t n : leaves) {
        const solve::QuadNode& node = f.node(n);
        const double w = std::max(0.0, std::min(u1, node.U(1)) - std::max(u0, node.U(0))) *
                         std::max(0.0, std::min(v1, node.V(1)) - std::max(v0, node.V(0)));
        if (w <= 0)
            continue;
        const double s = std::clamp(u / node.size() - node.i, 0.0, 1.0);
        const double t = std::clamp(v / node.size() - node.j, 0.0, 1.0);
        solve::EvalCoeffs(f.order(), f.value(n), f.blocks(), s, t, part);
        for (int b = 0; b < f.blocks(); ++b)
            out[b] += float(w) * part[b];
        total += w;
    }
    for (int b = 0; b < f.blocks(); ++b)
        out[b] = float(out[b] / total);
}

TEST(ContinuousField, OneDescentGivesTheFiveDescentsBits) {
    solve::ChartField f(2, 3);
    size_t n = 0;
    for (int level = 0; level < 6; ++level)  // uneven: deep towards (1/3, 2/3)
        n = size_t(f.Subdivide(n)) + (level % 2 ? 2 : 1);
    f.Subdivide(3);
    f.Subdivide(size_t(f.node(3).first_child));
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> coeff(0.5f, 2.f);
    for (size_t k = 0; k < f.node_count(); ++k)
        for (int c = 0; c < f.stride(); ++c)
            f.value(k)[c] = coeff(rng);  // every leaf its own fit: jumps at every border
    const ContinuousField shown(f, 1.0 / 512);
    const double delta = shown.delta();

    std::vector<double> at = {0, 1};
    for (size_t k = 0; k < f.node_count(); ++k)
        for (double x : {f.node(k).U(0), f.node(k).U(1), f.node(k).V(0), f.node(k).V(1)})
            for (double d : {0.0, delta, -delta, delta - 1e-5, 1e-5 - delta, delta / 2, -delta / 2})
                for (double y = x + d, z = x + d, i = 0; i < 3; ++i) {
                    at.push_back(y);
                    at.push_back(z);
                    y = std::nextafter(y, -1.0);
                    z = std::nextafter(z, 2.0);
                }
    std::uniform_real_distribution<double> any(0, 1);
    for (int k = 0; k < 200; ++k)
        at.push_back(any(rng));
    for (double& x : at)
        x = std::clamp(x, 0.0, 1.0);
    std::sort(at.begin(), at.end());
    at.erase(std::unique(at.begin(), at.end()), at.end());

    int one_leaf = 0, blended = 0;
    for (double u : at)
        for (double v : at) {
            float got[3], want[3], own[3];
            shown.Eval(u, v, got);
            Reference(f, delta, u, v, want);
            ASSERT_EQ(std::memcmp(got, want, sizeof got), 0) << u << " " << v;
            f.EvalValue(u, v, own);
            (std::memcmp(got, own, sizeof got) == 0 ? one_leaf : blended)++;
        }
    EXPECT_GT(one_leaf, 1000);  // both kinds of point were met
    EXPECT_GT(blended, 1000);
}

TEST(ContinuousField, TheLastLeafGivesLeafAtsBitsInAnyOrder) {
    solve::ChartField f(2, 3), g(1, 3);
    size_t n = 0;
    for (int level = 0; level < 5; ++level)
        n = size_t(f.Subdivide(n)) + (level % 2 ? 3 : 0);
    g.Subdivide(0);
    g.Subdivide(2);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> coeff(0.5f, 2.f);
    for (solve::ChartField* h : {&f, &g})
        for (size_t k = 0; k < h->node_count(); ++k)
            for (int c = 0; c < h->stride(); ++c)
                h->value(k)[c] = coeff(rng);
    const ContinuousField a(f, 1.0 / 1024), b(g, 1.0 / 1024);
    std::vector<std::pair<double, double>> at;
    std::uniform_real_distribution<double> any(0, 1);
    for (int k = 0; k < 4000; ++k)
        at.push_back({any(rng), any(rng)});
    for (size_t k = 0; k < f.node_count(); ++k)  // node corners and an ulp either side
        for (double du : {-1.0, 0.0, 1.0})
            at.push_back({std::clamp(std::nextafter(f.node(k).U(1), 2.0 * du), 0.0, 1.0),
                          std::clamp(f.node(k).V(0), 0.0, 1.0)});
    for (int pass = 0; pass < 2; ++pass) {
        for (size_t k = 0; k < at.size(); ++k) {
            const auto [u, v] = at[k];
            float got[3], want[3], other[3], other_want[3];
            a.Eval(u, v, got);
            Reference(f, a.delta(), u, v, want);
            ASSERT_EQ(std::memcmp(got, want, sizeof got), 0) << u << " " << v;
            if (k % 3 == 0) {  // another field between: the next point's last leaf is stale
                b.Eval(v, u, other);
                Reference(g, b.delta(), v, u, other_want);
                ASSERT_EQ(std::memcmp(other, other_want, sizeof other), 0) << v << " " << u;
            }
        }
        std::reverse(at.begin(), at.end());
    }
}

}  // namespace
}  // namespace mebake::output
