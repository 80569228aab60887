// The indirect transfer kernel (solve/transfer.h) the solver's gather runs: its far form is
// the transport formula, its texels add up to Lambert's closed form for a square, the near
// and far forms meet where the solver switches between them, and the near form stays
// bounded as the receiver approaches the texel.
#include "solve/transfer.h"

#include "solve/polygon_light.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace mebake::solve {
namespace {

// Unit radiosity B = 1 is radiance 1/pi.
constexpr double kUnitRadiance = 1.0 / std::numbers::pi;

TEST(Transfer, FarFormIsTheTransportFormula) {
    const Vec3f x{0.1f, -0.2f, 0.0f}, n{0, 0, 1};
    const TexelSource t{{0.3f, 0.4f, 2.0f}, Normalize(Vec3f{0.1f, -0.1f, -1.0f}), 0.01f};
    Vec3d e;
    ASSERT_TRUE(TexelTransfer(x, n, t, 0.1, &e));
    const Vec3d d = Vec3d(t.pos) - Vec3d(x);
    const double r2 = Dot(d, d), ce = -Dot(d, Vec3d(t.nrm));
    const Vec3d want = d * (double(t.area) * ce / (std::numbers::pi * r2 * r2));
    EXPECT_NEAR(e.x, want.x, 1e-12);
    EXPECT_NEAR(e.y, want.y, 1e-12);
    EXPECT_NEAR(e.z, want.z, 1e-12);
}

TEST(Transfer, TexelsOfASquareSumToLambertsFormula) {
    // A unit square at height 1 facing down, cut into k x k texels; x below its corner.
    const Vec3f x{0.2f, -0.3f, 0.0f}, n = Normalize(Vec3f{0.2f, 0.1f, 1.0f});
    for (int k : {16, 64}) {
        const double side = 1.0 / k;
        Vec3d sum{};
        for (int i = 0; i < k; ++i)
            for (int j = 0; j < k; ++j) {
                const TexelSource t{{float((i + 0.5) * side), float((j + 0.5) * side), 1.0f},
                                    {0, 0, -1},
                                    float(side * side)};
                Vec3d e;
                if (TexelTransfer(x, n, t, side, &e))
                    sum = sum + e;
            }
        const std::vector<Vec3d> square = {{0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}};
        const Vec3d want = VectorIrradiance(square, kUnitRadiance, Vec3d(x));
        EXPECT_NEAR(Length(sum - want) / Length(want), 0, k == 16 ? 5e-3 : 5e-4) << k;
    }
}

TEST(Transfer, NearAndFarFormsMeetAtTheSwitch) {
    // On either side of r = 2 texel sides the two forms describe the same texel.
    const double side = 0.05;
    const TexelSource t{{0, 0, 0}, {0, 0, 1}, float(side * side)};
    const Vec3f n = Normalize(Vec3f{0.3f, 0.0f, -1.0f});
    Vec3d near_e, far_e;
    ASSERT_TRUE(TexelTransfer(Vec3f{0.02f, 0.0f, float(2 * side * 0.999)}, n, t, side, &near_e));
    ASSERT_TRUE(TexelTransfer(Vec3f{0.02f, 0.0f, float(2 * side * 1.001)}, n, t, side, &far_e));
    EXPECT_NEAR(Length(near_e - far_e) / Length(far_e), 0, 0.03);
}

TEST(Transfer, NearFormStaysBoundedCloseToTheTexel) {
    // Just above the centre of a texel, it fills the hemisphere: |E| -> pi L = B = 1.
    const TexelSource t{{0, 0, 0}, {0, 0, 1}, 1e-4f};
    Vec3d e;
    ASSERT_TRUE(TexelTransfer(Vec3f{0, 0, 1e-7f}, {0, 0, -1}, t, 1e-2, &e));
    EXPECT_TRUE(std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z));
    EXPECT_NEAR(e.z, -1.0, 1e-2) << "E points from the receiver toward the source";
    EXPECT_LE(Length(e), 1.0 + 1e-9);
}

TEST(Transfer, NoLightFromBelowTheHorizonFromBehindOrFromX) {
    const TexelSource t{{0, 0, 1}, {0, 0, -1}, 0.01f};
    Vec3d e;
    EXPECT_FALSE(TexelTransfer({0, 0, 0}, {0, 0, -1}, t, 0.1, &e)) << "below the horizon";
    const TexelSource away{{0, 0, 1}, {0, 0, 1}, 0.01f};
    EXPECT_FALSE(TexelTransfer({0, 0, 0}, {0, 0, 1}, away, 0.1, &e)) << "facing away";
    EXPECT_FALSE(TexelTransfer({0, 0, 1}, {0, 0, 1}, t, 0.1, &e)) << "at x";
}


TEST(Transfer, FacetsAcrossAFoldCarryTheLightTheirMeanNormalLoses) {
    // A sample made of two facets folded 120 degrees apart (a ridge along y): the mean
    // normal is +z, the facets tilt 60 degrees to -x and +x. x lies off to the -x side,
    // slightly below the sample: only the -x facet faces it, the mean faces away.
    const double side = 0.1;
    const float a = float(side * side / 2);
    const float s60 = std::sqrt(3.f) / 2;
    const TexelSource west{{-0.025f, 0, 0}, {-s60, 0, 0.5f}, a}, east{{0.025f, 0, 0}, {s60, 0, 0.5f}, a};
    const TexelSource mean{{0, 0, 0}, {0, 0, 1}, 2 * a};
    const TexelSource facets[2] = {west, east};
    const Vec3f x{-1.0f, 0, -0.05f}, n = Normalize(Vec3f{1.0f, 0, 0.2f});
    Vec3d e_mean, e_west, e;
    int carrier = 7;
    EXPECT_FALSE(TexelTransfer(x, n, mean, side, &e_mean)) << "the mean faces away";
    ASSERT_TRUE(TexelTransfer(x, n, west, side / 2, &e_west));
    ASSERT_TRUE(FacetedTransfer(x, n, mean, facets, side, &e, &carrier));
    EXPECT_EQ(carrier, 0);
    EXPECT_NEAR(Length(e - e_west) / Length(e_west), 0, 1e-12) << "the west facet's own light";
    EXPECT_GT(Dot(e, Vec3d(n)), 0);
    // Facets all facing x: the sample as a whole, as before.
    const Vec3f above{0.3f, 0.2f, 2.0f}, down{0, 0, -1};
    Vec3d e_whole;
    ASSERT_TRUE(TexelTransfer(above, down, mean, side, &e_whole));
    ASSERT_TRUE(FacetedTransfer(above, down, mean, facets, side, &e, &carrier));
    EXPECT_EQ(carrier, -1);
    EXPECT_EQ(e.x, e_whole.x);
    EXPECT_EQ(e.z, e_whole.z);
    // No facets: TexelTransfer.
    ASSERT_TRUE(FacetedTransfer(above, down, mean, {}, side, &e, &carrier));
    EXPECT_EQ(e.z, e_whole.z);
}

// FacetsAgree lets the gather skip a sample's facets: wherever it says so, every facet must
// lie on the sample's side of x (so FacetedTransfer gives TexelTransfer's bits), and it must
// say so for most points a few sample sizes away, or it saves nothing. Random samples of
// four facets (tilted up to 60 degrees, offset up to half the sample's side, some of zero
// area), points near and far, a few within the rounding margin of a facet's plane.
TEST(Transfer, FacetsAgreeOnlyWhereEveryFacetFacesThePointOneWay) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    auto random_unit = [&](const Vec3f& around, float spread) {
        const Vec3f v = around + Vec3f(u(rng), u(rng), u(rng)) * spread;
        return Normalize(v);
    };
    int agreed = 0, far_points = 0, far_agreed = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const float side = 0.1f;
        const Vec3f centre(u(rng), u(rng), u(rng));
        const Vec3f axis = random_unit({0, 0, 0}, 1.f);
        const float tilt = trial % 3 == 0 ? 0.05f : 1.0f;
        TexelSource facets[4];
        for (auto& f : facets) {
            const float area = u(rng) < -0.8f ? 0.f : side * side / 4;
            f = {centre + Vec3f(u(rng), u(rng), u(rng)) * (side / 2), random_unit(axis, tilt),
                 area};
        }
        const TexelSource t{centre, axis, side * side};
        const FacetSpread spread = SpreadOf(t, facets);
        const float reach = trial % 2 ? 0.3f : 5.f;
        Vec3f x = centre + Vec3f(u(rng), u(rng), u(rng)) * reach;
        if (trial % 50 == 0)  // on a facet's plane, where the exact test is a coin toss
            x = facets[0].pos + Normalize(Cross(facets[0].nrm, Vec3f(1, 0, 0))) * reach;
        int toward = 0, real = 0;
        for (const auto& f : facets) {
            if (f.area <= 0)
                continue;
            ++real;
            toward += Dot(Vec3d(x) - Vec3d(f.pos), Vec3d(f.nrm)) > 0 ? 1 : 0;
        }
        const bool far = Length(x - centre) > 20 * side && tilt < 0.1f;
        far_points += far ? 1 : 0;
        if (!FacetsAgree(x, t, spread))
            continue;
        ++agreed;
        far_agreed += far ? 1 : 0;
        ASSERT_TRUE(toward == 0 || toward == real) << "trial " << trial;
        // And the sample's own side is theirs.
        const double own = Dot(Vec3d(x) - Vec3d(t.pos), Vec3d(t.nrm));
        if (real > 0) {
            ASSERT_EQ(own > 0, toward == real) << "trial " << trial;
        }
        const Vec3f n = Normalize(Vec3f(t.pos - x));
        Vec3d e_whole{}, e{};
        int carrier = 7;
        const bool whole = TexelTransfer(x, n, t, side, &e_whole);
        ASSERT_EQ(FacetedTransfer(x, n, t, facets, side, &e, &carrier), whole);
        EXPECT_EQ(carrier, -1);
        EXPECT_EQ(e.x, e_whole.x);
        EXPECT_EQ(e.y, e_whole.y);
        EXPECT_EQ(e.z, e_whole.z);
    }
    EXPECT_GT(agreed, 5000);
    // Nearly flat samples seen from 20 sample sizes or more: most skip the facets (89 %;
    // the others lie near the plane, where the facets' offsets decide).
    EXPECT_GT(far_agreed, 0.85 * far_points) << far_agreed << " of " << far_points;
}

// FacetsAgree compares squares (no root): it must decide as the test with the root,
// side > offset + sqrt(r2) x tilt, everywhere but within its 1e-9 widening of the bound, or
// the gather would read more facets than before (the bytes are the same either way: the
// test above). Random sides, distances and spreads, some on the bound itself.
TEST(Transfer, FacetsAgreeWithoutTheRootDecidesAsWithIt) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    int agreed = 0, differ = 0;
    for (int trial = 0; trial < 200000; ++trial) {
        PairGeometry g;
        g.r2 = std::pow(10.0, 6 * u(rng) - 3);
        FacetSpread spread;
        spread.offset = float(trial % 7 == 0 ? 0.0 : 0.01 * u(rng));
        spread.tilt = float(trial % 5 == 0 ? 0.0 : u(rng));
        const double bound = spread.offset + std::sqrt(g.r2) * spread.tilt;
        g.ce = (trial % 2 ? 1 : -1) *
               (trial % 100 == 0 ? bound * (1 + (u(rng) - 0.5) * 1e-12) : 2 * bound * u(rng));
        const bool rooted = std::abs(g.ce) > spread.offset &&
                            std::abs(g.ce) > spread.offset + std::sqrt(g.r2) * spread.tilt;
        const bool squared = FacetsAgree(g, spread);
        agreed += squared ? 1 : 0;
        if (squared == rooted)
            continue;
        ++differ;
        // Only a hair from the bound, and only ever on the safe side (reading the facets).
        EXPECT_TRUE(rooted) << "trial " << trial;
        EXPECT_LT(std::abs(std::abs(g.ce) - bound), 1e-8 * (bound + 1e-300)) << "trial " << trial;
    }
    EXPECT_GT(agreed, 50000);
    EXPECT_LT(differ, 2000);
}

// BelowHorizon lets the gather skip the facets of a sample below a receiver's horizon:
// wherever it says so, FacetedTransfer must return false (random samples of four facets as
// above, receivers near them with random normals, some within the rounding margin), and it
// must say so for most receivers that see the whole sample well below their horizon.
TEST(Transfer, BelowHorizonOnlyWhereNoFacetCanPass) {
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    auto random_unit = [&](const Vec3f& around, float spread) {
        return Normalize(around + Vec3f(u(rng), u(rng), u(rng)) * spread);
    };
    int below = 0, deep = 0, deep_below = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const float side = 0.1f;
        const Vec3f centre(u(rng), u(rng), u(rng));
        const Vec3f axis = random_unit({0, 0, 0}, 1.f);
        TexelSource facets[4];
        for (auto& f : facets) {
            const float area = u(rng) < -0.8f ? 0.f : side * side / 4;
            f = {centre + Vec3f(u(rng), u(rng), u(rng)) * (side / 2), random_unit(axis, 1.f),
                 area};
        }
        const TexelSource t{centre, axis, side * side};
        const FacetSpread spread = SpreadOf(t, facets);
        const Vec3f x = centre + Vec3f(u(rng), u(rng), u(rng)) * (trial % 2 ? 0.3f : 2.f);
        Vec3f n = random_unit({0, 0, 0}, 1.f);
        if (trial % 50 == 0)  // a facet's centre just on the horizon
            n = Normalize(Cross(facets[0].pos - x, Vec3f(0, 0, 1)));
        const PairGeometry g = GeometryOf(x, t);
        // The highest of the centres above x's tangent plane (facets of zero area do not count).
        double highest = Dot(Vec3d(t.pos) - Vec3d(x), Vec3d(n));
        for (const auto& f : facets)
            if (f.area > 0)
                highest = std::max(highest, Dot(Vec3d(f.pos) - Vec3d(x), Vec3d(n)));
        const bool is_deep = highest < -0.2 * side;
        deep += is_deep ? 1 : 0;
        if (!BelowHorizon(g, n, spread))
            continue;
        ++below;
        deep_below += is_deep ? 1 : 0;
        Vec3d e;
        int carrier = 7;
        ASSERT_FALSE(FacetedTransfer(x, n, t, facets, side, &e, &carrier)) << "trial " << trial;
        ASSERT_LE(highest, 0) << "trial " << trial;
    }
    EXPECT_GT(below, 2000);
    // Receivers with the sample and its facets a fifth of its side below the horizon: the
    // bound (the facets within `reach` of the centre, in every direction) finds most.
    EXPECT_GT(deep_below, 0.5 * deep) << deep_below << " of " << deep;
}

// RegionBelowHorizon and RegionFacesAway let the gather skip a link's whole region for a
// receiver point: wherever either says so, no pair of the region may carry light, by either
// path of the gather (FacetedTransfer with the facets, TexelTransfer alone where they agree),
// also for receivers placed just on a part's plane; and they must find most receivers for
// which the whole region lies well below the horizon or wholly behind its parts.
TEST(Transfer, RegionCullsOnlyWhereNoPairCanPass) {
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    auto random_unit = [&](const Vec3f& around, float spread) {
        return Normalize(around + Vec3f(u(rng), u(rng), u(rng)) * spread);
    };
    struct Sample {
        TexelSource t;
        TexelSource facets[4];
        FacetSpread spread;
    };
    int culled_below = 0, culled_away = 0, clear = 0, clear_culled = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        // A region of 2 x 2 or 4 x 4 samples of side `side` on a gently curved sheet.
        const float side = 0.05f;
        const int span = trial % 2 ? 2 : 4;
        const Vec3f axis = random_unit({0, 0, 0}, 1.f);
        const Vec3f tu = Normalize(Cross(axis, Vec3f(0.3f, 0.5f, 0.8f)));
        const Vec3f tv = Cross(axis, tu);
        const float bend = trial % 3 == 0 ? 1.f : 0.2f;
        const Vec3f origin(u(rng), u(rng), u(rng));
        std::vector<Sample> samples;
        RegionBound region{origin, axis};
        for (int b = 0; b < span; ++b)
            for (int a = 0; a < span; ++a) {
                Sample smp;
                const Vec3f pos = origin + tu * (a * side) + tv * (b * side) +
                                  axis * (bend * side * u(rng));
                const Vec3f nrm = random_unit(axis, bend * 0.5f);
                smp.t = {pos, nrm, side * side};
                for (auto& f : smp.facets)
                    f = {pos + Vec3f(u(rng), u(rng), u(rng)) * (side / 2),
                         random_unit(nrm, bend * 0.5f), u(rng) < -0.9f ? 0.f : side * side / 4};
                smp.spread = SpreadOf(smp.t, smp.facets);
                region.Add(pos, nrm, smp.spread.reach, smp.spread.tilt);
                samples.push_back(smp);
            }
        for (int k = 0; k < 20; ++k) {
            const Sample& s0 = samples[size_t(k) % samples.size()];
            Vec3f x = origin + Vec3f(u(rng), u(rng), u(rng)) * (k % 2 ? 0.3f : 2.f);
            Vec3f n = random_unit({0, 0, 0}, 1.f);
            if (k % 5 == 0)  // x just on a facet's plane, or a facet's centre on x's horizon
                x = s0.facets[0].pos + Cross(s0.facets[0].nrm, Vec3f(0, 1, 0)) * 0.5f;
            if (k % 5 == 1)
                n = Normalize(Cross(s0.facets[1].pos - x, Vec3f(0, 0, 1)));
            // The highest part above x's plane, and the part x sees most from the front.
            double highest = -1e30, front = -1e30;
            for (const Sample& smp : samples) {
                highest = std::max(highest, Dot(Vec3d(smp.t.pos) - Vec3d(x), Vec3d(n)));
                front = std::max(front, Dot(Vec3d(x) - Vec3d(smp.t.pos), Vec3d(smp.t.nrm)));
                for (const auto& f : smp.facets)
                    if (f.area > 0) {
                        highest = std::max(highest, Dot(Vec3d(f.pos) - Vec3d(x), Vec3d(n)));
                        front = std::max(front, Dot(Vec3d(x) - Vec3d(f.pos), Vec3d(f.nrm)));
                    }
            }
            const bool below = RegionBelowHorizon(x, n, region);
            const bool away = RegionFacesAway(x, region);
            const bool is_clear = highest < -0.5 * side || front < -0.5 * side;
            clear += is_clear ? 1 : 0;
            if (!below && !away)
                continue;
            culled_below += below ? 1 : 0;
            culled_away += away ? 1 : 0;
            clear_culled += is_clear ? 1 : 0;
            if (below) {
                ASSERT_LE(highest, 0) << "trial " << trial;
            }
            if (away) {
                ASSERT_LE(front, 0) << "trial " << trial;
            }
            for (const Sample& smp : samples) {
                Vec3d e;
                int carrier = 7;
                ASSERT_FALSE(FacetedTransfer(x, n, smp.t, smp.facets, side, &e, &carrier))
                    << "trial " << trial;
                ASSERT_FALSE(TexelTransfer(x, n, smp.t, side, &e)) << "trial " << trial;
            }
        }
    }
    EXPECT_GT(culled_below, 5000);
    EXPECT_GT(culled_away, 5000);
    // Most receivers that see the whole region half a sample below their horizon or behind
    // all of its parts are found.
    EXPECT_GT(clear_culled, 0.5 * clear) << clear_culled << " of " << clear;
}

}  // namespace
}  // namespace mebake::solve
