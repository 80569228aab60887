#include "solve/polygon_light.h"

#include "solve/basis.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

namespace mebake::solve {
namespace {

struct Tri {
    Vec3d a, b, c;
};

// The transport (docs/method.md) integrated by brute force over triangles: each triangle is split into
// 4^levels pieces, each integrated with the collapsed (Duffy) 8x8 Gauss rule.
// dE(x) = B max(0,(x-y).n) (y-x) / (pi |y-x|^4) dA, B = pi L; with `receiver_n` the integrand
// is instead L max(0, cos theta_x) cos theta_y / r^2 (the horizon-clipped irradiance).
struct BruteForce {
    Vec3d front;  // emitter front normal
    double radiance = 1;
    bool two_sided = false;

    Vec3d Integrand(const Vec3d& x, const Vec3d& y) const {
        const Vec3d d = y - x;
        const double r2 = Dot(d, d);
        double cos_term = Dot(x - y, front);
        if (two_sided)
            cos_term = std::abs(cos_term);
        if (cos_term <= 0)
            return {};
        const double b = M_PI * radiance;
        return d * (b * cos_term / (M_PI * r2 * r2));
    }

    void Accumulate(const Tri& t, const Vec3d& x, const Vec3d* n, int levels, Vec3d* e,
                    double* irr) const {
        if (levels > 0) {
            const Vec3d ab = (t.a + t.b) * 0.5, bc = (t.b + t.c) * 0.5, ca = (t.c + t.a) * 0.5;
            const Tri parts[4] = {{t.a, ab, ca}, {ab, t.b, bc}, {ca, bc, t.c}, {ab, bc, ca}};
            for (const Tri& p : parts)
                Accumulate(p, x, n, levels - 1, e, irr);
            return;
        }
        const GaussRule& g = Gauss(8);
        const double area2 = Length(Cross(t.b - t.a, t.c - t.a));
        for (int i = 0; i < 8; ++i) {
            for (int j = 0; j < 8; ++j) {
                const double u = g.x[i], v = g.x[j];
                const Vec3d y = t.a + ((t.b - t.a) + (t.c - t.b) * v) * u;
                const double w = g.w[i] * g.w[j] * u * area2;
                const Vec3d f = Integrand(x, y);
                *e += f * w;
                if (n)
                    *irr += std::max(0.0, Dot(*n, Normalize(y - x))) * Length(f) * w;
            }
        }
    }

    Vec3d E(const std::vector<Tri>& tris, const Vec3d& x, int levels = 3) const {
        Vec3d e;
        double irr = 0;
        for (const Tri& t : tris)
            Accumulate(t, x, nullptr, levels, &e, &irr);
        return e;
    }
    double Irradiance(const std::vector<Tri>& tris, const Vec3d& x, const Vec3d& n,
                      int levels) const {
        Vec3d e;
        double irr = 0;
        for (const Tri& t : tris)
            Accumulate(t, x, &n, levels, &e, &irr);
        return irr;
    }
};

std::vector<Tri> Fan(const std::vector<Vec3d>& p) {
    std::vector<Tri> t;
    for (size_t k = 1; k + 1 < p.size(); ++k)
        t.push_back({p[0], p[k], p[k + 1]});
    return t;
}

// A square [-h,h]^2 at height z, counter-clockwise seen from below (it emits downwards).
std::vector<Vec3d> CeilingSquare(double h, double z) {
    return {{-h, -h, z}, {-h, h, z}, {h, h, z}, {h, -h, z}};
}

// EdgeAngle is within one unit in the last place of std::atan2 over every octant, near the
// reduction's switch points (tan = 0.66, 1) and at extreme ratios; and exact where
// atan2 is (a right angle, a straight one's limit).
TEST(PolygonLight, EdgeAngleIsAtan2WithinOneUlp) {
    auto ulps = [](double a, double b) {
        return std::abs(a - b) / std::abs(std::nextafter(a, 10.0) - a);
    };
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<std::pair<double, double>> cases;
    for (int i = 0; i < 200000; ++i)
        cases.push_back({std::abs(u(rng)) * std::pow(10.0, 4 * u(rng)) + 1e-300,
                         u(rng) * std::pow(10.0, 4 * u(rng))});
    for (double r : {0.66, 1.0, 1 / 0.66}) {
        for (int k = -20; k <= 20; ++k) {
            const double y = r * (1 + k * 1e-15);
            cases.push_back({y, 1.0});
            cases.push_back({y, -1.0});
        }
    }
    for (double y : {1e-300, 1e-20, 1e20, 1e300}) {
        cases.push_back({y, 1.0});
        cases.push_back({y, -1.0});
        cases.push_back({1.0, y});
        cases.push_back({1.0, -y});
    }
    double worst = 0;
    for (const auto& [y, x] : cases)
        worst = std::max(worst, ulps(std::atan2(y, x), EdgeAngle(y, x)));
    EXPECT_LE(worst, 1.0);
    EXPECT_EQ(EdgeAngle(1.0, 0.0), std::atan2(1.0, 0.0));
    EXPECT_EQ(EdgeAngle(1.0, 1.0), std::atan2(1.0, 1.0));
}

// LambertEdge is LambertSum's term (the same bits summed in the same order), and its sums
// are additive as the penumbra's shared edges need (penumbra.cpp's EdgeTable): an edge
// reversed is the term negated, an edge split at a point on it the same term.
TEST(PolygonLight, LambertEdgeIsTheSumsTermAndAdditive) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int trial = 0; trial < 1000; ++trial) {
        const Vec3d v[3] = {{u(rng), 2 + u(rng), u(rng)}, {u(rng), 2 + u(rng), u(rng)},
                            {u(rng), 2 + u(rng), u(rng)}};
        const Vec3d x(u(rng), u(rng), u(rng));
        Vec3d sum;
        for (int k = 0; k < 3; ++k)
            sum += LambertEdge(v[k], v[(k + 1) % 3], x);
        const Vec3d whole = LambertSum(v, 3, x);
        EXPECT_EQ(sum.x, whole.x);
        EXPECT_EQ(sum.y, whole.y);
        EXPECT_EQ(sum.z, whole.z);
        const Vec3d there = LambertEdge(v[0], v[1], x), back = LambertEdge(v[1], v[0], x);
        const Vec3d m = v[0] + (v[1] - v[0]) * (0.25 + 0.5 * (u(rng) + 1) / 2);
        const Vec3d halves = LambertEdge(v[0], m, x) + LambertEdge(m, v[1], x);
        const double scale = Length(there);
        EXPECT_LT(Length(there + back), 1e-14 * scale);
        EXPECT_LT(Length(there - halves), 1e-12 * scale);
    }
    // x on the edge's line: no term.
    const Vec3d zero = LambertEdge({0, 0, 0}, {1, 0, 0}, {2, 0, 0});
    EXPECT_EQ(Length(zero), 0.0);
}

TEST(PolygonLight, NormalAndAreaFollowTheWinding) {
    auto sq = CeilingSquare(1, 2);
    EXPECT_NEAR(PolygonNormal(sq).z, -1.0, 1e-15);
    EXPECT_NEAR(PolygonArea(sq), 4.0, 1e-15);
    std::vector<Vec3d> line = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    EXPECT_EQ(Length(PolygonNormal(line)), 0.0);
}

TEST(PolygonLight, LargeLightAbovePointsUpAndGivesPiL) {
    const double L = 2.5;
    auto sq = CeilingSquare(500, 1);  // side 1e3 at distance 1
    Vec3d e = VectorIrradiance(sq, L, {0, 0, 0});
    EXPECT_GT(e.z, 0);  // towards the light: irradiance of an upward receiver is n.E > 0
    EXPECT_NEAR(e.z / (M_PI * L), 1.0, 1e-5);
    EXPECT_NEAR(e.x, 0.0, 1e-12);
    EXPECT_NEAR(e.y, 0.0, 1e-12);
    EXPECT_NEAR(IrradianceClipped(sq, L, {0, 0, 0}, {0, 0, 1}) / (M_PI * L), 1.0, 1e-5);
}

TEST(PolygonLight, SmallFarLightMatchesPointSource) {
    // 1 cm square, tilted, 10 m away: E.n -> L A cos_x cos_y / d^2.
    const double L = 3, h = 0.005;
    const Vec3d c{4, -3, 8};
    const Vec3d ne = Normalize(Vec3d{-0.2, 0.1, -1});  // front normal, roughly downwards
    const Vec3d u = Normalize(Cross(ne, Vec3d{1, 0, 0}));
    const Vec3d v = Cross(ne, u);
    // Counter-clockwise about ne: u, v, -u, -v corners.
    std::vector<Vec3d> poly = {c + (u + v) * h, c + (v - u) * h, c - (u + v) * h, c + (u - v) * h};
    ASSERT_NEAR(Dot(PolygonNormal(poly), ne), 1.0, 1e-12);
    const Vec3d x{0.5, 0.2, 0}, n = Normalize(Vec3d{0.1, 0.3, 1});
    const Vec3d d = c - x;
    const double dist = Length(d);
    const double expected = L * (4 * h * h) * Dot(n, d / dist) * Dot(ne, -d / dist) / (dist * dist);
    const Vec3d e = VectorIrradiance(poly, L, x);
    EXPECT_NEAR(Dot(n, e) / expected, 1.0, 1e-6);
    EXPECT_NEAR(Dot(Normalize(e), d / dist), 1.0, 1e-9);
    EXPECT_NEAR(IrradianceClipped(poly, L, x, n) / expected, 1.0, 1e-6);
}

TEST(PolygonLight, ParallelUnitSquaresFormFactor) {
    // Emitter [0,1]^2 at z=1 facing down; receiver [0,1]^2 at z=0 facing up.
    std::vector<Vec3d> em = {{0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}};
    const double L = 1.7;
    const GaussRule& g = Gauss(8);
    const int cells = 4;
    double f = 0;
    for (int ci = 0; ci < cells; ++ci) {
        for (int cj = 0; cj < cells; ++cj) {
            for (int a = 0; a < 8; ++a) {
                for (int b = 0; b < 8; ++b) {
                    const Vec3d x{(ci + g.x[a]) / cells, (cj + g.x[b]) / cells, 0};
                    const double w = g.w[a] * g.w[b] / (cells * cells);
                    f += w * VectorIrradiance(em, L, x).z / (M_PI * L);
                }
            }
        }
    }
    EXPECT_NEAR(f, 0.19982, 1e-4);
    EXPECT_NEAR(f, 0.1998248, 2e-6);  // tabulated value of the parallel unit-squares factor
}

// Random rigid motion applied to a planar polygon built in the xy plane (counter-clockwise
// seen from +z, so the front is +z before the motion).
std::vector<Vec3d> Place(const std::vector<Vec3d>& poly2d, std::mt19937& rng, Vec3d* front) {
    std::normal_distribution<double> nd;
    Vec3d ax = Normalize(Vec3d{nd(rng), nd(rng), nd(rng)});
    Vec3d tmp = Normalize(Vec3d{nd(rng), nd(rng), nd(rng)});
    Vec3d ay = Normalize(Cross(tmp, ax));
    Vec3d az = Cross(ax, ay);
    Vec3d t{nd(rng), nd(rng), nd(rng)};
    std::vector<Vec3d> out;
    for (const Vec3d& p : poly2d)
        out.push_back(t + ax * p.x + ay * p.y + az * p.z);
    *front = az;
    return out;
}

TEST(PolygonLight, MatchesBruteForceTransportAtRandomPoints) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.5, 1.5);
    // Convex and non-convex shapes with their triangulations (in the local xy plane).
    struct Shape {
        std::vector<Vec3d> poly;
        std::vector<std::array<int, 3>> tris;
    };
    std::vector<Shape> shapes = {
        {{{0, 0, 0}, {1, 0, 0}, {0.3, 0.8, 0}}, {{0, 1, 2}}},
        {{{-0.5, -0.4, 0}, {0.5, -0.4, 0}, {0.5, 0.4, 0}, {-0.5, 0.4, 0}}, {{0, 1, 2}, {0, 2, 3}}},
        // L-shape (non-convex).
        {{{0, 0, 0}, {1, 0, 0}, {1, 0.4, 0}, {0.4, 0.4, 0}, {0.4, 1, 0}, {0, 1, 0}},
         {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 5}}},
        {{{1, 0, 0}, {0.31, 0.95, 0}, {-0.81, 0.59, 0}, {-0.81, -0.59, 0}, {0.31, -0.95, 0}},
         {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}}},
    };
    int checked = 0;
    double max_rel = 0;
    for (const Shape& shape : shapes) {
        for (int rep = 0; rep < 3; ++rep) {
            Vec3d front;
            std::vector<Vec3d> poly = Place(shape.poly, rng, &front);
            ASSERT_NEAR(Dot(PolygonNormal(poly), front), 1.0, 1e-12);
            std::vector<Tri> tris;
            for (auto& t : shape.tris)
                tris.push_back({poly[t[0]], poly[t[1]], poly[t[2]]});
            for (int two = 0; two < 2; ++two) {
                BruteForce bf{front, 1.3, two == 1};
                const Emission em = two ? Emission::kBoth : Emission::kFront;
                for (int i = 0; i < 20; ++i) {
                    Vec3d x = poly[0] + Vec3d{u(rng), u(rng), u(rng)};
                    const double dist = Dot(x - poly[0], front);
                    if (std::abs(dist) < 0.3)
                        continue;  // well separated only
                    const Vec3d ref = bf.E(tris, x);
                    const Vec3d e = VectorIrradiance(poly, 1.3, x, em);
                    if (dist < 0 && !two) {
                        EXPECT_EQ(Length(e), 0.0);
                        continue;
                    }
                    EXPECT_LT(Length(e - ref), 1e-6 * Length(ref))
                        << "x=" << x.x << "," << x.y << "," << x.z << " e=" << e.x << "," << e.y
                        << "," << e.z << " ref=" << ref.x << "," << ref.y << "," << ref.z;
                    ++checked;
                    max_rel = std::max(max_rel, Length(e - ref) / Length(ref));
                }
            }
        }
    }
    EXPECT_GT(checked, 150);
    std::printf("%d points, max relative error vs brute force %.3g\n", checked, max_rel);
}

TEST(PolygonLight, HorizonClippingMatchesTheUpperPart) {
    // Square [-1,1]^2 at z=1 facing down, receiver at the origin tilted about y: its tangent
    // plane cuts the square along X = -0.3, so the visible part is the rectangle X > -0.3.
    auto sq = CeilingSquare(1, 1);
    const Vec3d x{0, 0, 0}, n = Normalize(Vec3d{1, 0, 0.3});
    std::vector<Vec3d> upper = {{-0.3, -1, 1}, {-0.3, 1, 1}, {1, 1, 1}, {1, -1, 1}};
    BruteForce bf{{0, 0, -1}, 2.0, false};
    const double ref = Dot(n, bf.E(Fan(upper), x, 4));
    const double got = IrradianceClipped(sq, 2.0, x, n);
    EXPECT_NEAR(got / ref, 1.0, 1e-9);
    // Unclipped n.E is smaller: the part below the horizon subtracts.
    EXPECT_LT(Dot(n, VectorIrradiance(sq, 2.0, x)), got - 1e-3);
    // All above: clipping changes nothing. All below: nothing.
    EXPECT_NEAR(IrradianceClipped(sq, 2.0, x, {0, 0, 1}), VectorIrradiance(sq, 2.0, x).z, 1e-12);
    EXPECT_EQ(IrradianceClipped(sq, 2.0, x, {0, 0, -1}), 0.0);
}

TEST(PolygonLight, HorizonClippingMatchesBruteForceForRandomNormals) {
    std::mt19937 rng(12);
    std::normal_distribution<double> nd;
    // Non-convex L-shape on the ceiling, facing down.
    std::vector<Vec3d> poly = {{0, 0, 1},     {0, 1, 1},   {0.4, 1, 1},
                               {0.4, 0.4, 1}, {1, 0.4, 1}, {1, 0, 1}};
    ASSERT_NEAR(PolygonNormal(poly).z, -1.0, 1e-15);
    std::vector<Tri> tris = {{poly[0], poly[1], poly[2]},
                             {poly[0], poly[2], poly[3]},
                             {poly[0], poly[3], poly[4]},
                             {poly[0], poly[4], poly[5]}};
    BruteForce bf{{0, 0, -1}, 1.0, false};
    for (int i = 0; i < 12; ++i) {
        const Vec3d x{0.5 + 0.5 * nd(rng), 0.5 + 0.5 * nd(rng), 0.2 * nd(rng)};
        const Vec3d n = Normalize(Vec3d{nd(rng), nd(rng), nd(rng)});
        const double ref = bf.Irradiance(tris, x, n, 5);
        const double got = IrradianceClipped(poly, 1.0, x, n);
        EXPECT_NEAR(got, ref, 1e-3 * std::max(ref, 0.05)) << i;
    }
}

TEST(PolygonLight, BackSideAndPlaneAndEdges) {
    auto sq = CeilingSquare(1, 1);
    // Above a downward-facing light: nothing for one-sided, mirrored for two-sided.
    EXPECT_EQ(Length(VectorIrradiance(sq, 1, {0.2, 0.1, 2})), 0.0);
    Vec3d below = VectorIrradiance(sq, 1, {0.2, 0.1, 0}, Emission::kBoth);
    Vec3d above = VectorIrradiance(sq, 1, {0.2, 0.1, 2}, Emission::kBoth);
    EXPECT_NEAR(above.z, -below.z, 1e-12);
    EXPECT_NEAR(above.x, below.x, 1e-12);
    // On the plane, inside and outside: zero.
    EXPECT_EQ(Length(VectorIrradiance(sq, 1, {0.2, 0.1, 1}, Emission::kBoth)), 0.0);
    EXPECT_EQ(Length(VectorIrradiance(sq, 1, {3, 0, 1})), 0.0);
    // On a vertex, an edge, and extremely close to an edge: finite and bounded by pi L.
    const Vec3d probes[] = {{1, 1, 1},
                            {1, 0, 1},
                            {1, 0, 1 - 1e-13},
                            {1 + 1e-12, 0, 1 - 1e-9},
                            {1 - 1e-9, 0.3, 1 - 1e-12},
                            {0.999999, 0, 0.99999999}};
    for (const Vec3d& p : probes) {
        for (Emission em : {Emission::kFront, Emission::kBoth}) {
            Vec3d e = VectorIrradiance(sq, 1, p, em);
            ASSERT_TRUE(std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z));
            EXPECT_LE(Length(e), M_PI * (1 + 1e-9));
            double irr = IrradianceClipped(sq, 1, p, {0, 0, 1}, em);
            ASSERT_TRUE(std::isfinite(irr));
            EXPECT_LE(irr, M_PI * (1 + 1e-9));
        }
    }
    // Just in front of the interior the light fills the hemisphere: E -> pi L (0, 0, 1).
    Vec3d near = VectorIrradiance(sq, 1, {0.2, 0.1, 1 - 1e-9});
    EXPECT_NEAR(near.z, M_PI, 1e-6);
    // Degenerate polygons give zero, not NaN.
    std::vector<Vec3d> line = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    EXPECT_EQ(Length(VectorIrradiance(line, 1, {0, 1, 1})), 0.0);
    EXPECT_EQ(IrradianceClipped(std::span<const Vec3d>(sq.data(), 2), 1, {0, 0, 0}, {0, 0, 1}),
              0.0);
}


// ClipToHalfSpace takes each vertex's side once (an edge's dq is the next edge's dp): the
// same vertices to the bit as the per-edge form it replaced, on random polygons and planes.
TEST(PolygonLight, ClipToHalfSpaceMatchesThePerEdgeForm) {
    auto per_edge = [](const Vec3d* v, int nv, const Vec3d& x, const Vec3d& n, Vec3d* out) {
        int nc = 0;
        for (int k = 0; k < nv; ++k) {
            const Vec3d& p = v[k];
            const Vec3d& q = v[k + 1 == nv ? 0 : k + 1];
            const double dp = Dot(p - x, n), dq = Dot(q - x, n);
            if (dp >= 0) out[nc++] = p;
            if ((dp >= 0) != (dq >= 0)) out[nc++] = p + (q - p) * (dp / (dp - dq));
        }
        return nc;
    };
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    int clipped = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const int nv = 3 + trial % 6;
        std::vector<Vec3d> poly(static_cast<size_t>(nv));
        for (auto& p : poly) p = {u(rng), u(rng), u(rng)};
        const Vec3d x{u(rng) * 0.5, u(rng) * 0.5, u(rng) * 0.5}, n{u(rng), u(rng), u(rng)};
        std::vector<Vec3d> want(2 * size_t(nv)), got(2 * size_t(nv));
        const int nw = per_edge(poly.data(), nv, x, n, want.data());
        const int ng = ClipToHalfSpace(poly.data(), nv, x, n, got.data());
        ASSERT_EQ(ng, nw) << "trial " << trial;
        for (int k = 0; k < ng; ++k)
            for (int c = 0; c < 3; ++c)
                ASSERT_EQ(got[size_t(k)][c], want[size_t(k)][c]) << "trial " << trial;
        int above = 0;
        for (const Vec3d& p : poly) above += Dot(p - x, n) >= 0;
        clipped += above > 0 && above < nv;
    }
    EXPECT_GT(clipped, 500);  // the planes cut most polygons
    EXPECT_EQ(ClipToHalfSpace(nullptr, 0, {}, {0, 0, 1}, nullptr), 0);
}

}  // namespace
}  // namespace mebake::solve
