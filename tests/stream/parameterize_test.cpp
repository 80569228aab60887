#include "stream/parameterize.h"

#include "core/parallel.h"
#include "stream/arap.h"
#include "stream/chart_builder.h"
#include "stream/square_fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fmt/format.h>
#include <functional>
#include <memory>
#include <numbers>
#include <random>

namespace mebake::stream {
namespace {

constexpr double kPi = std::numbers::pi;

// An n x n vertex grid over [0,1]^2 with jittered interior vertices and randomly chosen
// quad diagonals, counter-clockwise, mapped to 3D by `surface`.
TriMesh GridPatch(int n, uint32_t seed, const std::function<Vec3d(double, double)>& surface,
                  double jitter = 0.3) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> jit(-jitter, jitter);
    std::bernoulli_distribution coin(0.5);
    TriMesh m;
    const double h = 1.0 / (n - 1);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            double x = i * h, y = j * h;
            if (i > 0 && i < n - 1)
                x += jit(rng) * h;
            if (j > 0 && j < n - 1)
                y += jit(rng) * h;
            m.position.push_back(Vec3f(surface(x, y)));
        }
    }
    auto id = [n](int i, int j) {
        return uint32_t(j * n + i);
    };
    for (int j = 0; j + 1 < n; ++j) {
        for (int i = 0; i + 1 < n; ++i) {
            const uint32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
            if (coin(rng)) {
                m.triangles.push_back({a, b, c});
                m.triangles.push_back({a, c, d});
            } else {
                m.triangles.push_back({a, b, d});
                m.triangles.push_back({b, c, d});
            }
        }
    }
    return m;
}

Vec3d Plane(double x, double y) {
    // A 1.3 x 0.8 rectangle in a tilted plane.
    const Vec3d o(0.2, -0.4, 1.0), e1 = Normalize(Vec3d(1, 0.5, 0.3));
    const Vec3d e2 = Normalize(Cross(Vec3d(0.2, -0.1, 1), e1));
    return o + e1 * (1.3 * x) + e2 * (0.8 * y);
}

Vec3d QuarterCylinder(double x, double y) {
    const double t = x * kPi / 2;
    return {std::cos(t), std::sin(t), 1.2 * y};
}

// The square mapped to a disc (Shirley-Chiu concentric map), then onto the unit sphere's
// cap of half-angle `cap`, by geodesic distance from the pole.
std::function<Vec3d(double, double)> SphereCap(double cap) {
    return [cap](double x, double y) {
        const double a = 2 * x - 1, b = 2 * y - 1;
        double r = 0, phi = 0;
        if (a * a > b * b) {
            r = a;
            phi = (kPi / 4) * (b / a);
        } else if (b != 0) {
            r = b;
            phi = kPi / 2 - (kPi / 4) * (a / b);
        }
        const double px = r * std::cos(phi), py = r * std::sin(phi);
        const double rho = std::hypot(px, py), psi = std::atan2(py, px);
        const double theta = rho * cap;
        return Vec3d(std::sin(theta) * std::cos(psi), std::sin(theta) * std::sin(psi),
                     std::cos(theta));
    };
}

// A scan-like height field: a few smooth bumps plus per-vertex noise.
std::function<Vec3d(double, double)> Bumpy(double amplitude, double noise, uint32_t seed) {
    auto rng = std::make_shared<std::mt19937>(seed);
    return [=](double x, double y) {
        std::uniform_real_distribution<double> u(-1, 1);
        const double z = amplitude * (std::sin(5.1 * x + 0.3) * std::cos(4.3 * y - 0.2) +
                                      0.5 * std::sin(11.0 * x * y + 1.0)) +
                         noise * u(*rng);
        return Vec3d(x, y, z);
    };
}

void ExpectValid(const TriMesh& m, const ChartParam& p, double margin = 1.0 / 64) {
    ASSERT_TRUE(HasUv(p.status)) << p.message;
    ASSERT_EQ(p.uv.size(), m.vertex_count());
    ASSERT_EQ(p.area_ratio.size(), m.triangle_count());
    EXPECT_EQ(p.metrics.flipped, 0u);
    float lo_x = 1, hi_x = 0, lo_y = 1, hi_y = 0;
    for (const Vec2f& q : p.uv) {
        ASSERT_TRUE(q.x >= 0 && q.x <= 1 && q.y >= 0 && q.y <= 1) << fmt::format("{}", q);
        lo_x = std::min(lo_x, q.x);
        hi_x = std::max(hi_x, q.x);
        lo_y = std::min(lo_y, q.y);
        hi_y = std::max(hi_y, q.y);
    }
    // The longer side spans [margin, 1 - margin], the shorter one is centred.
    const float side = std::max(hi_x - lo_x, hi_y - lo_y);
    EXPECT_NEAR(side, 1 - 2 * margin, 1e-5);
    EXPECT_NEAR(lo_x + hi_x, 1.0, 1e-5);
    EXPECT_NEAR(lo_y + hi_y, 1.0, 1e-5);
    for (const auto& f : m.triangles) {
        const Vec2f a = p.uv[f[0]], b = p.uv[f[1]], c = p.uv[f[2]];
        ASSERT_GT(Cross(b - a, c - a), 0.f);
    }
    EXPECT_GT(p.scale, 0);
    EXPECT_GE(p.metrics.virtual_fraction, 0);
    EXPECT_LT(p.metrics.virtual_fraction, 1);
}

// Max relative error of |uv edge| * s against the 3D edge length.
double EdgeLengthError(const TriMesh& m, const ChartParam& p) {
    double worst = 0;
    for (const auto& f : m.triangles) {
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = f[k], b = f[(k + 1) % 3];
            const double l3 = Length(Vec3d(m.position[a]) - Vec3d(m.position[b]));
            const Vec2d d(double(p.uv[a].x) - p.uv[b].x, double(p.uv[a].y) - p.uv[b].y);
            worst = std::max(worst, std::abs(Length(d) * p.scale / l3 - 1));
        }
    }
    return worst;
}

void Print(const char* name, const ChartParam& p) {
    const ParamMetrics& m = p.metrics;
    std::printf("%-16s dev mean %.2e p95 %.2e max %.2e coarse %.2e  conformal mean %.4f max %.3f  "
                "virtual %.3f  refine it %d  init flips %u  %s\n",
                name, m.jacobian_deviation_mean, m.jacobian_deviation_p95, m.jacobian_deviation_max,
                m.jacobian_deviation_coarse, m.conformal_mean, m.conformal_max, m.virtual_fraction,
                m.refine_iterations, m.init_flipped, ParamStatusName(p.status));
}

ParamOptions LscmOnly() {
    ParamOptions o;
    o.init = ParamInit::kLscm;
    o.refine = false;
    return o;
}

ParamOptions BffOnly() {
    ParamOptions o;
    o.refine = false;
    return o;
}

TEST(ParameterizeChart, PlaneIsAnIsometry) {
    const TriMesh m = GridPatch(33, 1, Plane);
    ASSERT_EQ(m.triangle_count(), 2048u);
    const char* names[] = {"plane lscm", "plane bff", "plane refined"};
    const ParamOptions options[] = {LscmOnly(), BffOnly(), ParamOptions{}};
    for (int i = 0; i < 3; ++i) {
        const ChartParam p = ParameterizeChart(m, options[i]);
        Print(names[i], p);
        ASSERT_EQ(p.status, ParamStatus::kOk) << p.message;
        ExpectValid(m, p);
        EXPECT_LT(p.metrics.jacobian_deviation_mean, 1e-4);
        EXPECT_LT(p.metrics.jacobian_deviation_max, 1e-3);
        EXPECT_LT(p.metrics.conformal_mean - 1, 1e-4);
        EXPECT_LT(EdgeLengthError(m, p), 1e-3);
        // The 1.3 x 0.8 rectangle: its long side spans 1 - 2 margin in uv, 1.3 in 3D.
        EXPECT_NEAR(p.scale * (1 - 2.0 / 64), 1.3, 1e-4);
        EXPECT_NEAR(p.metrics.virtual_fraction, 1 - 1.3 * 0.8 / (p.scale * p.scale), 1e-4);
    }
}

TEST(UvOverlapFraction, SharedEdgesAreNotOverlapsAndStackedTrianglesAre) {
    const std::vector<Vec2f> uv = {{0.1f, 0.1f}, {0.9f, 0.1f}, {0.9f, 0.9f}, {0.1f, 0.9f},
                                   {0.3f, 0.3f}, {0.7f, 0.3f}, {0.3f, 0.7f}};
    const std::vector<std::array<uint32_t, 3>> square = {{0, 1, 2}, {0, 2, 3}};
    EXPECT_EQ(UvOverlapFraction(square, uv, 512), 0.0);
    std::vector<std::array<uint32_t, 3>> stacked = square;
    stacked.push_back({4, 5, 6});  // 0.08 of the square's 0.64, covered twice
    EXPECT_NEAR(UvOverlapFraction(stacked, uv, 512), 0.08 / 0.64, 0.01);
}

// The grid scan UvOverlapFraction replaced: every centre of each triangle's bounding box
// tested with the three edge functions.
double OverlapByEveryCentre(const std::vector<std::array<uint32_t, 3>>& triangles,
                            const std::vector<Vec2f>& uv, uint32_t res) {
    std::vector<uint8_t> hit(size_t(res) * res, 0);
    const float r = float(res);
    size_t covered = 0, twice = 0;
    for (const auto& t : triangles) {
        const Vec2f a = uv[t[0]], b = uv[t[1]], c = uv[t[2]];
        const auto edge = [](Vec2f p, Vec2f q, float x, float y) {
            return (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
        };
        const int i0 = std::max(0, int(std::floor(std::min({a.x, b.x, c.x}) * r - 0.5f)));
        const int i1 = std::min(int(res) - 1, int(std::ceil(std::max({a.x, b.x, c.x}) * r - 0.5f)));
        const int j0 = std::max(0, int(std::floor(std::min({a.y, b.y, c.y}) * r - 0.5f)));
        const int j1 = std::min(int(res) - 1, int(std::ceil(std::max({a.y, b.y, c.y}) * r - 0.5f)));
        for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i) {
                const float x = (float(i) + 0.5f) / r, y = (float(j) + 0.5f) / r;
                const float w0 = edge(a, b, x, y), w1 = edge(b, c, x, y), w2 = edge(c, a, x, y);
                if (!((w0 > 0 && w1 > 0 && w2 > 0) || (w0 < 0 && w1 < 0 && w2 < 0)))
                    continue;
                uint8_t& h = hit[size_t(j) * res + size_t(i)];
                covered += h == 0;
                twice += h == 1;
                h = uint8_t(std::min(2, h + 1));
            }
    }
    return covered ? double(twice) / double(covered) : 0;
}

// Row intervals instead of every centre: the same fraction, to the bit, on soups of both
// orientations with corners on texel centres and on texel edges (edge functions exactly
// 0), horizontal and vertical edges, slivers, degenerate and off-square triangles.
TEST(UvOverlapFraction, RowIntervalsCountTheSameCentresAsTestingEveryOne) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> any(-0.1f, 1.1f), near(-0.03f, 0.03f);
    for (const uint32_t res : {7u, 16u, 64u, 512u}) {
        std::uniform_int_distribution<int> cell(0, int(res));
        for (int soup = 0; soup < 200; ++soup) {
            std::vector<Vec2f> uv;
            std::vector<std::array<uint32_t, 3>> tris;
            auto corner = [&](int kind) {
                if (kind == 0)
                    return Vec2f(any(rng), any(rng));
                // On a texel centre (kind 1) or a texel edge (kind 2) of the grid.
                const float o = kind == 1 ? 0.5f : 0.0f;
                return Vec2f((float(cell(rng)) + o) / float(res), (float(cell(rng)) + o) / float(res));
            };
            for (int k = 0; k < 30; ++k) {
                const uint32_t v = uint32_t(uv.size());
                const int kind = int(rng() % 3);
                const Vec2f a = corner(kind);
                Vec2f b = corner(kind), c = corner(kind);
                switch (rng() % 6) {
                case 0: b.y = a.y; break;                         // a horizontal edge
                case 1: c.x = a.x; break;                         // a vertical edge
                case 2: b = a + Vec2f(near(rng), near(rng));      // small
                        c = a + Vec2f(near(rng), near(rng)); break;
                case 3: c = a + (b - a) * 0.37f; break;           // (nearly) collinear
                case 4: c = a; break;                             // a repeated corner
                default: break;
                }
                uv.insert(uv.end(), {a, b, c});
                tris.push_back(rng() % 2 ? std::array<uint32_t, 3>{v, v + 1, v + 2}
                                         : std::array<uint32_t, 3>{v, v + 2, v + 1});
            }
            ASSERT_EQ(UvOverlapFraction(tris, uv, res), OverlapByEveryCentre(tris, uv, res))
                << "res " << res << " soup " << soup;
        }
    }
}

// A ramp winding one and a half turns around an axis, rising slowly: nearly isometric to a
// flat annulus of 540 degrees, so its natural flattening has no flipped triangle but
// covers a third of itself twice. It must not pass as a chart.
TEST(ParameterizeChart, RampWindingOnItselfOverlaps) {
    const TriMesh m = GridPatch(17, 7, [](double x, double y) {
        const double angle = 3 * kPi * y, r = 1 + 0.5 * x;
        return Vec3d(r * std::cos(angle), r * std::sin(angle), 0.05 * angle);
    }, 0);
    const ChartParam p = ParameterizeChart(m, ParamOptions{});
    ASSERT_TRUE(HasUv(p.status)) << p.message;
    EXPECT_EQ(p.metrics.flipped, 0u);
    EXPECT_EQ(p.status, ParamStatus::kOverlap) << p.message;
    EXPECT_GT(UvOverlapFraction(m.triangles, p.uv, kOverlapResolution), 0.1);
}

TEST(ParameterizeChart, QuarterCylinderIsDevelopable) {
    const TriMesh m = GridPatch(33, 2, QuarterCylinder);
    const ChartParam lscm = ParameterizeChart(m, LscmOnly());
    const ChartParam refined = ParameterizeChart(m);
    Print("cylinder lscm", lscm);
    Print("cylinder refined", refined);
    ExpectValid(m, lscm);
    ExpectValid(m, refined);
    EXPECT_LT(lscm.metrics.jacobian_deviation_mean, 1e-2);
    EXPECT_LT(refined.metrics.jacobian_deviation_mean, 1e-3);
    EXPECT_LT(refined.metrics.conformal_mean - 1, 1e-3);
    EXPECT_LT(EdgeLengthError(m, refined), 1e-2);
    // The developed quarter cylinder is a pi/2 x 1.2 rectangle (chords shorten it a bit).
    EXPECT_NEAR(refined.metrics.area_3d, kPi / 2 * 1.2, 2e-3);
    EXPECT_NEAR(refined.scale * (1 - 2.0 / 64), kPi / 2, 2e-3);
    const double side = 1 - 2.0 / 64;
    EXPECT_NEAR(refined.metrics.virtual_fraction, 1 - side * side * 1.2 / (kPi / 2), 2e-3);
}

TEST(ParameterizeChart, SphereCapHasBoundedDistortion) {
    for (const double degrees : {30.0, 60.0, 85.0}) {
        const TriMesh m = GridPatch(41, 3, SphereCap(degrees * kPi / 180), 0.2);
        const ChartParam lscm = ParameterizeChart(m, LscmOnly());
        const ChartParam refined = ParameterizeChart(m);
        const std::string name = fmt::format("cap {:.0f} ", degrees);
        Print((name + "lscm").c_str(), lscm);
        Print((name + "refined").c_str(), refined);
        ExpectValid(m, refined);
        // Plain LSCM folds a sliver at the 85-degree cap's rim; only the refined map must
        // be flip-free.
        if (degrees < 80)
            ExpectValid(m, lscm);
        // Conformal maps blow areas up towards the rim; the refinement trades a little
        // shear for a nearly constant area ratio (an equal-area map of a cap of half-angle
        // a needs shear 1 / cos^2(a / 2): 1.07 at 30 degrees, 1.33 at 60).
        EXPECT_LT(lscm.metrics.jacobian_deviation_mean, 0.4);
        EXPECT_GT(lscm.metrics.jacobian_deviation_mean, 0.05);
        if (degrees < 80) {
            EXPECT_LT(refined.metrics.jacobian_deviation_mean, 0.005);
            EXPECT_LT(refined.metrics.jacobian_deviation_coarse, 0.002);
            EXPECT_LT(refined.metrics.conformal_mean, degrees < 45 ? 1.06 : 1.2);
            EXPECT_EQ(refined.status, ParamStatus::kOk);
        } else {
            // Near a hemisphere the shear cap (1.5) binds: the chart should be split.
            EXPECT_LT(refined.metrics.jacobian_deviation_mean, 0.05);
            EXPECT_GT(refined.metrics.jacobian_deviation_coarse, 0.01);
            EXPECT_EQ(refined.status, ParamStatus::kDistorted);
        }
    }
}

TEST(ParameterizeChart, BumpyScanLikePatch) {
    // A 64 x 64 patch: bumps of 10% of its size plus per-vertex noise of 0.3 edge lengths.
    const TriMesh m = GridPatch(65, 4, Bumpy(0.1, 0.3 / 64, 7));
    const ChartParam lscm = ParameterizeChart(m, LscmOnly());
    const ChartParam refined = ParameterizeChart(m);
    Print("bumpy lscm", lscm);
    Print("bumpy refined", refined);
    ExpectValid(m, refined);
    EXPECT_EQ(refined.status, ParamStatus::kOk) << refined.message;
    EXPECT_LT(refined.metrics.jacobian_deviation_mean, 0.1 * lscm.metrics.jacobian_deviation_mean);
    EXPECT_LT(refined.metrics.jacobian_deviation_mean, 0.02);
    EXPECT_LT(refined.metrics.jacobian_deviation_p95, 0.05);
    EXPECT_LT(refined.metrics.jacobian_deviation_coarse, 0.003);
    EXPECT_LT(refined.metrics.conformal_mean, 1.15);
}

TEST(ParameterizeChart, RoughPatchIsNotSplitForNoise) {
    // Noise of a full edge length: no flat map keeps triangle areas, but the area per
    // quadtree cell is kept, so the chart is accepted (splitting would not help).
    const TriMesh m = GridPatch(65, 5, Bumpy(0.1, 1.0 / 64, 8));
    const ChartParam p = ParameterizeChart(m);
    Print("rough refined", p);
    ExpectValid(m, p);
    EXPECT_GT(p.metrics.jacobian_deviation_mean, 0.02);
    EXPECT_LT(p.metrics.jacobian_deviation_coarse, 0.01);
    EXPECT_EQ(p.status, ParamStatus::kOk) << p.message;
}

TEST(ParameterizeChart, LongStripFillsTheSquareDiagonally) {
    // A flat 8 x 1 strip: the best rotation puts it on the square's diagonal, so its long
    // side is longer than the square's side would allow axis-aligned.
    const TriMesh m = GridPatch(33, 6, [](double x, double y) { return Vec3d(8 * x, y, 0); });
    const ChartParam p = ParameterizeChart(m);
    ExpectValid(m, p);
    const double axis_aligned_virtual = 1 - (1 - 2.0 / 64) * (1 - 2.0 / 64) / 8;
    EXPECT_LT(p.metrics.virtual_fraction, axis_aligned_virtual - 0.01);
}

TEST(ParameterizeChart, Deterministic) {
    const TriMesh m = GridPatch(41, 5, Bumpy(0.1, 0.01, 9));
    const ChartParam a = ParameterizeChart(m);
    ChartParam b;
    {
        const ThreadLimit one_thread(1);
        b = ParameterizeChart(m);
    }
    ASSERT_EQ(a.uv.size(), b.uv.size());
    EXPECT_EQ(std::memcmp(a.uv.data(), b.uv.data(), a.uv.size() * sizeof(Vec2f)), 0);
    EXPECT_EQ(a.scale, b.scale);
    EXPECT_EQ(a.metrics.jacobian_deviation_mean, b.metrics.jacobian_deviation_mean);
}

TEST(ParameterizeChart, AreaRatiosMatchTheDefinition) {
    const TriMesh m = GridPatch(21, 6, SphereCap(0.8));
    const ChartParam p = ParameterizeChart(m);
    ASSERT_TRUE(HasUv(p.status));
    double misplaced = 0, total = 0, uv_area = 0;
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        const auto& f = m.triangles[t];
        const Vec3d p0(m.position[f[0]]);
        const double a3 =
            0.5 * Length(Cross(Vec3d(m.position[f[1]]) - p0, Vec3d(m.position[f[2]]) - p0));
        const Vec2f a = p.uv[f[0]], b = p.uv[f[1]], c = p.uv[f[2]];
        const double auv = 0.5 * double(Cross(b - a, c - a));
        EXPECT_NEAR(p.area_ratio[t], a3 / (auv * p.scale * p.scale), 1e-3 * p.area_ratio[t]);
        misplaced += std::abs(a3 - auv * p.scale * p.scale);
        total += a3;
        uv_area += auv;
    }
    EXPECT_NEAR(p.metrics.jacobian_deviation_mean, misplaced / total, 1e-6);
    EXPECT_NEAR(p.metrics.virtual_fraction, 1 - uv_area, 1e-5);
    EXPECT_NEAR(total, p.scale * p.scale * uv_area, 1e-6 * total);
}

// --- rejections ---

TriMesh ClosedSphere(int n) {
    // A latitude-longitude sphere with single vertices at the poles.
    TriMesh m;
    m.position.push_back({0, 0, 1});
    for (int j = 1; j < n; ++j) {
        const double th = kPi * j / n;
        for (int i = 0; i < 2 * n; ++i) {
            const double ph = kPi * i / n;
            m.position.push_back(Vec3f(
                Vec3d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th))));
        }
    }
    m.position.push_back({0, 0, -1});
    const uint32_t south = uint32_t(m.position.size() - 1);
    auto id = [n](int j, int i) {
        return uint32_t(1 + (j - 1) * 2 * n + (i % (2 * n)));
    };
    for (int i = 0; i < 2 * n; ++i)
        m.triangles.push_back({0, id(1, i), id(1, i + 1)});
    for (int j = 1; j + 1 < n; ++j) {
        for (int i = 0; i < 2 * n; ++i) {
            m.triangles.push_back({id(j, i), id(j + 1, i), id(j + 1, i + 1)});
            m.triangles.push_back({id(j, i), id(j + 1, i + 1), id(j, i + 1)});
        }
    }
    for (int i = 0; i < 2 * n; ++i)
        m.triangles.push_back({south, id(n - 1, i + 1), id(n - 1, i)});
    return m;
}

TriMesh Annulus(int rings, int segments) {
    TriMesh m;
    for (int j = 0; j <= rings; ++j) {
        const double r = 1 + double(j) / rings;
        for (int i = 0; i < segments; ++i) {
            const double a = 2 * kPi * i / segments;
            m.position.push_back(Vec3f(Vec3d(r * std::cos(a), r * std::sin(a), 0)));
        }
    }
    auto id = [segments](int j, int i) {
        return uint32_t(j * segments + i % segments);
    };
    for (int j = 0; j < rings; ++j) {
        for (int i = 0; i < segments; ++i) {
            m.triangles.push_back({id(j, i), id(j, i + 1), id(j + 1, i + 1)});
            m.triangles.push_back({id(j, i), id(j + 1, i + 1), id(j + 1, i)});
        }
    }
    return m;
}

TEST(ParameterizeChart, RejectsClosedSphere) {
    const TriMesh m = ClosedSphere(12);
    const ChartParam p = ParameterizeChart(m);
    EXPECT_EQ(p.status, ParamStatus::kNotDisc) << p.message;
    EXPECT_TRUE(p.uv.empty());
    EXPECT_NE(p.message.find("closed"), std::string::npos) << p.message;
}

TEST(ParameterizeChart, RejectsAnnulus) {
    const TriMesh m = Annulus(4, 24);
    const ChartParam p = ParameterizeChart(m);
    EXPECT_EQ(p.status, ParamStatus::kNotDisc) << p.message;
    EXPECT_NE(p.message.find("boundary loops"), std::string::npos) << p.message;
}

TEST(ParameterizeChart, RejectsMalformedCharts) {
    const TriMesh good = GridPatch(5, 8, Plane);
    ASSERT_EQ(ParameterizeChart(good).status, ParamStatus::kOk);

    EXPECT_EQ(ParameterizeChart(TriMesh{}).status, ParamStatus::kEmpty);

    TriMesh bad_index = good;
    bad_index.triangles[3][1] = 1000;
    EXPECT_EQ(ParameterizeChart(bad_index).status, ParamStatus::kBadIndex);

    TriMesh repeated = good;
    repeated.triangles[3][1] = repeated.triangles[3][0];
    EXPECT_EQ(ParameterizeChart(repeated).status, ParamStatus::kBadIndex);

    TriMesh nan = good;
    nan.position[7].y = std::nanf("");
    EXPECT_EQ(ParameterizeChart(nan).status, ParamStatus::kNonFinite);

    TriMesh flipped_face = good;  // inconsistent orientation
    std::swap(flipped_face.triangles[10][0], flipped_face.triangles[10][1]);
    EXPECT_EQ(ParameterizeChart(flipped_face).status, ParamStatus::kNonManifold);

    TriMesh fin = good;  // a third triangle on an interior edge
    fin.position.push_back({5, 5, 5});
    const auto& f = fin.triangles[10];
    fin.triangles.push_back({f[1], f[0], uint32_t(fin.position.size() - 1)});
    EXPECT_EQ(ParameterizeChart(fin).status, ParamStatus::kNonManifold);

    TriMesh unreferenced = good;
    unreferenced.position.push_back({1, 1, 1});
    EXPECT_EQ(ParameterizeChart(unreferenced).status, ParamStatus::kNotDisc);

    // Two copies side by side: two components.
    TriMesh two = good;
    const uint32_t offset = uint32_t(two.position.size());
    for (const Vec3f& q : good.position)
        two.position.push_back(q + Vec3f(3, 0, 0));
    for (const auto& t : good.triangles)
        two.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    EXPECT_EQ(ParameterizeChart(two).status, ParamStatus::kNotDisc);

    // The same two copies sharing one corner vertex: a pinched (bowtie) vertex.
    TriMesh bowtie = two;
    const uint32_t corner_a = 24, corner_b = offset;  // (1,1) of the first, (0,0) of the second
    for (auto& t : bowtie.triangles)
        for (uint32_t& v : t)
            if (v == corner_b)
                v = corner_a;
    bowtie.position[corner_b] = bowtie.position[corner_a];
    // Vertex corner_b is now unreferenced; drop it by moving the last vertex into its slot.
    const uint32_t last = uint32_t(bowtie.position.size() - 1);
    bowtie.position[corner_b] = bowtie.position[last];
    bowtie.position.pop_back();
    for (auto& t : bowtie.triangles)
        for (uint32_t& v : t)
            if (v == last)
                v = corner_b;
    const ChartParam p = ParameterizeChart(bowtie);
    EXPECT_EQ(p.status, ParamStatus::kNonManifold) << p.message;
}

TEST(ParameterizeChart, DegenerateTrianglesAreSurvived) {
    // Interior vertices moved onto a neighbour's edge line: zero-area triangles inside.
    TriMesh m = GridPatch(17, 10, Plane, 0);
    for (const int i : {3, 7, 11}) {
        const uint32_t v = uint32_t(5 * 17 + i);
        m.position[v] = (m.position[v - 1] + m.position[v + 1]) * 0.5f;
    }
    const ChartParam p = ParameterizeChart(m);
    ASSERT_TRUE(HasUv(p.status)) << p.message;
    for (const Vec2f& q : p.uv)
        EXPECT_TRUE(q.x >= 0 && q.x <= 1 && q.y >= 0 && q.y <= 1);
    EXPECT_LT(p.metrics.jacobian_deviation_mean, 0.01);

    // Everything on one line: nothing to flatten.
    TriMesh line = GridPatch(
        5, 11, [](double x, double) { return Vec3d(x, 0, 0); }, 0);
    EXPECT_EQ(ParameterizeChart(line).status, ParamStatus::kDegenerate);
}

TEST(CheckDisc, ReturnsTheBoundaryLoopInWindingOrder) {
    const TriMesh m = GridPatch(4, 9, Plane, 0);
    const DiscCheck c = CheckDisc(uint32_t(m.vertex_count()), m.triangles);
    ASSERT_EQ(c.status, ParamStatus::kOk) << c.message;
    ASSERT_EQ(c.boundary.size(), 12u);
    // Counter-clockwise in the grid's (i, j) plane: the signed area is positive.
    double area = 0;
    for (size_t k = 0; k < c.boundary.size(); ++k) {
        const uint32_t a = c.boundary[k], b = c.boundary[(k + 1) % c.boundary.size()];
        const double ax = a % 4, ay = a / 4, bx = b % 4, by = b / 4;
        area += ax * by - bx * ay;
    }
    EXPECT_NEAR(area / 2, 9, 1e-12);
}

TEST(ParameterizeChart, TorusWithHoleHasWrongEuler) {
    // A torus grid with one quad removed: one boundary loop, connected, but genus 1.
    const int n = 8, k = 6;
    TriMesh m;
    for (int j = 0; j < k; ++j)
        for (int i = 0; i < n; ++i) {
            const double a = 2 * kPi * i / n, b = 2 * kPi * j / k;
            m.position.push_back(Vec3f(Vec3d((2 + std::cos(b)) * std::cos(a),
                                             (2 + std::cos(b)) * std::sin(a), std::sin(b))));
        }
    auto id = [&](int i, int j) {
        return uint32_t((j % k) * n + (i % n));
    };
    for (int j = 0; j < k; ++j)
        for (int i = 0; i < n; ++i) {
            if (i == 0 && j == 0)
                continue;
            m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    const ChartParam p = ParameterizeChart(m);
    EXPECT_EQ(p.status, ParamStatus::kNotDisc) << p.message;
    EXPECT_NE(p.message.find("Euler"), std::string::npos) << p.message;
}

// --- square fit ---

TEST(SquareFit, FindsTheRotationOfARectangle) {
    std::vector<Vec2d> pts;
    const double angle = 0.4;
    const Vec2d d(std::cos(angle), std::sin(angle)), n(-d.y, d.x);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0, 1);
    for (int i = 0; i < 200; ++i)
        pts.push_back(d * (3 * u(rng)) + n * (1 * u(rng)));
    for (const Vec2d& c : {Vec2d(0, 0), Vec2d(3, 0), Vec2d(3, 1), Vec2d(0, 1)})
        pts.push_back(d * c.x + n * c.y);
    for (const auto objective :
         {SquareFitObjective::kMinArea, SquareFitObjective::kMinLongerSide}) {
        const SquareFit fit = FitUnitSquare(pts, 0.1, objective);
        if (objective == SquareFitObjective::kMinArea) {
            EXPECT_NEAR(std::max(fit.width, fit.height), 3, 1e-9);
            EXPECT_NEAR(std::min(fit.width, fit.height), 1, 1e-9);
        } else {
            // Turned 45 degrees the 3 x 1 rectangle fits a square of side 4 / sqrt(2).
            EXPECT_NEAR(fit.width, 4 / std::sqrt(2.0), 1e-9);
            EXPECT_NEAR(fit.height, 4 / std::sqrt(2.0), 1e-9);
        }
        for (const Vec2d& p : pts) {
            const Vec2d q = fit.Apply(p);
            EXPECT_GE(q.x, 0.1 - 1e-12);
            EXPECT_LE(q.x, 0.9 + 1e-12);
            EXPECT_GE(q.y, 0.1 - 1e-12);
            EXPECT_LE(q.y, 0.9 + 1e-12);
        }
    }
}

TEST(SquareFit, LongerSideObjectiveBeatsMinArea) {
    // A long thin diagonal strip plus a blob: the min-area rectangle hugs the strip, the
    // min-longer-side one turns to use the square's diagonal room.
    std::vector<Vec2d> pts = {{0, 0}, {10, 0.2}, {10, 0.8}, {0, 1}, {5, 3}};
    const SquareFit area = FitUnitSquare(pts, 0, SquareFitObjective::kMinArea);
    const SquareFit side = FitUnitSquare(pts, 0, SquareFitObjective::kMinLongerSide);
    EXPECT_LE(std::max(side.width, side.height), std::max(area.width, area.height) + 1e-12);
    // Brute force over angles: the calipers found the optimum.
    double best = INFINITY;
    for (int i = 0; i < 200000; ++i) {
        const double a = (kPi / 2) * i / 200000;
        const Vec2d d(std::cos(a), std::sin(a)), n(-d.y, d.x);
        double lo_d = INFINITY, hi_d = -INFINITY, lo_n = INFINITY, hi_n = -INFINITY;
        for (const Vec2d& p : pts) {
            lo_d = std::min(lo_d, Dot(p, d));
            hi_d = std::max(hi_d, Dot(p, d));
            lo_n = std::min(lo_n, Dot(p, n));
            hi_n = std::max(hi_n, Dot(p, n));
        }
        best = std::min(best, std::max(hi_d - lo_d, hi_n - lo_n));
    }
    EXPECT_LE(std::max(side.width, side.height), best + 1e-9);
    EXPECT_GT(std::max(side.width, side.height), best - 1e-6);
}

TEST(SquareFit, ConvexHullDropsInteriorAndCollinearPoints) {
    const std::vector<Vec2d> pts = {{0, 0}, {1, 0}, {2, 0}, {2, 2},    {1, 1},
                                    {0, 2}, {0, 1}, {2, 2}, {0.5, 0.5}};
    const std::vector<Vec2d> hull = ConvexHull(pts);
    ASSERT_EQ(hull.size(), 4u);
    EXPECT_EQ(hull[0], Vec2d(0, 0));
    EXPECT_EQ(hull[1], Vec2d(2, 0));
    EXPECT_EQ(hull[2], Vec2d(2, 2));
    EXPECT_EQ(hull[3], Vec2d(0, 2));
}

}  // namespace
}  // namespace mebake::stream

namespace mebake::stream {
namespace {

// Ingest runs fewer refinement iterations than the defaults (ChartBuildOptions): the
// developable patches must still map with ~zero area and angle distortion and the caps
// within the bounds the defaults are held to (a little looser on the 60-degree cap).
TEST(ParameterizeChart, IngestIterationCountKeepsTheBounds) {
    ParamOptions o;
    o.refine_options.max_iterations = ChartBuildOptions{}.refine_iterations;
    const TriMesh plane = GridPatch(33, 1, Plane);
    const TriMesh cylinder = GridPatch(33, 2, QuarterCylinder);
    for (const TriMesh* m : {&plane, &cylinder}) {
        const ChartParam p = ParameterizeChart(*m, o);
        Print(m == &plane ? "plane ingest" : "cylinder ingest", p);
        ASSERT_EQ(p.status, ParamStatus::kOk) << p.message;
        ExpectValid(*m, p);
        EXPECT_LT(p.metrics.jacobian_deviation_mean, 1e-3);
        EXPECT_LT(p.metrics.conformal_mean - 1, 1e-3);
        EXPECT_LT(EdgeLengthError(*m, p), 1e-2);
    }
    for (const double degrees : {30.0, 60.0}) {
        const TriMesh m = GridPatch(41, 3, SphereCap(degrees * kPi / 180), 0.2);
        const ChartParam p = ParameterizeChart(m, o);
        Print(degrees < 45 ? "cap 30 ingest" : "cap 60 ingest", p);
        ExpectValid(m, p);
        EXPECT_EQ(p.status, ParamStatus::kOk);
        EXPECT_LT(p.metrics.jacobian_deviation_mean, 0.008);
        EXPECT_LT(p.metrics.jacobian_deviation_coarse, 0.002);
        EXPECT_LT(p.metrics.conformal_mean, degrees < 45 ? 1.06 : 1.2);
    }
}

}  // namespace
}  // namespace mebake::stream
