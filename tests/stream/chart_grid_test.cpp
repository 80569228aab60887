#include "stream/chart_grid.h"

#include "stream/parameterize.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fmt/format.h>
#include <functional>
#include <numbers>
#include <random>
#include <tuple>

namespace mebake::stream {
namespace {

constexpr double kPi = std::numbers::pi;
using Tris = std::vector<std::array<uint32_t, 3>>;
constexpr double kInside2 = 0x1p-44;  // (2^-22)^2: Locate's tolerance, squared

// An n x n jittered grid over [0,1]^2 mapped by `surface`; cells for which `keep` is
// false are left out (to cut notches).
TriMesh GridPatch(int n, uint32_t seed, const std::function<Vec3d(double, double)>& surface,
                  const std::function<bool(int, int)>& keep = nullptr) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> jit(-0.25, 0.25);
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
            if (keep && !keep(i, j))
                continue;
            m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    }
    // Drop unreferenced vertices.
    std::vector<uint32_t> remap(m.position.size(), ~0u);
    std::vector<Vec3f> kept;
    for (auto& t : m.triangles) {
        for (uint32_t& v : t) {
            if (remap[v] == ~0u) {
                remap[v] = uint32_t(kept.size());
                kept.push_back(m.position[v]);
            }
            v = remap[v];
        }
    }
    m.position = std::move(kept);
    return m;
}

Vec3d Cap(double x, double y) {  // a 70-degree-wide spherical patch
    const double a = (x - 0.5) * 1.2, b = (y - 0.5) * 1.2;
    return Normalize(Vec3d(a, b, 1.0));
}

struct Brute {
    double dist2 = INFINITY;
    uint32_t triangle = kNoTriangle;
};

Vec2d D(const Vec2f& v) {
    return {v.x, v.y};
}

double SegmentDist2(const Vec2d& u, const Vec2d& a, const Vec2d& b) {
    const Vec2d e = b - a;
    const double l2 = Dot(e, e);
    const double t = l2 > 0 ? std::clamp(Dot(u - a, e) / l2, 0.0, 1.0) : 0.0;
    const Vec2d q = a + e * t;
    return Dot(u - q, u - q);
}

// Distance from u to triangle t (0 inside), independent of the grid's code.
double TriDist2(const std::vector<Vec2f>& uv, const std::array<uint32_t, 3>& f, const Vec2d& u) {
    const Vec2d a = D(uv[f[0]]), b = D(uv[f[1]]), c = D(uv[f[2]]);
    const double s0 = Cross(b - a, u - a), s1 = Cross(c - b, u - b), s2 = Cross(a - c, u - c);
    const bool inside = (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
    if (inside && Cross(b - a, c - a) != 0)
        return 0;
    return std::min({SegmentDist2(u, a, b), SegmentDist2(u, b, c), SegmentDist2(u, c, a)});
}

Brute BruteNearest(const std::vector<Vec2f>& uv, const Tris& tris, const Vec2d& u) {
    Brute best;
    for (uint32_t t = 0; t < tris.size(); ++t) {
        const double d2 = TriDist2(uv, tris[t], u);
        if (d2 < best.dist2) {
            best.dist2 = d2;
            best.triangle = t;
        }
    }
    return best;
}

Vec2d Interpolate(const std::vector<Vec2f>& uv, const std::array<uint32_t, 3>& f,
                  const std::array<float, 3>& b) {
    return D(uv[f[0]]) * b[0] + D(uv[f[1]]) * b[1] + D(uv[f[2]]) * b[2];
}

// Checks Locate against brute force on `samples` points; returns how many were virtual.
int CheckAgainstBruteForce(const ChartGrid& grid, const std::vector<Vec2f>& samples) {
    int virtual_count = 0;
    for (const Vec2f& s : samples) {
        const GridLocation loc = grid.Locate(s);
        const Vec2d u = D(s);
        const Brute brute = BruteNearest(grid.uv, grid.triangles, u);
        EXPECT_NE(loc.triangle, kNoTriangle);
        if (loc.triangle == kNoTriangle)
            return virtual_count;
        EXPECT_NEAR(loc.barycentric[0] + loc.barycentric[1] + loc.barycentric[2], 1.0, 1e-6);
        for (float b : loc.barycentric)
            EXPECT_GE(b, 0.f);
        const double own2 = TriDist2(grid.uv, grid.triangles[loc.triangle], u);
        if (loc.real) {
            EXPECT_LE(own2, kInside2)
                << fmt::format("{} said real in triangle {}", s, loc.triangle);
            EXPECT_LT(
                Length(Interpolate(grid.uv, grid.triangles[loc.triangle], loc.barycentric) - u),
                1e-6);
            continue;
        }
        ++virtual_count;
        // Virtual: really outside, and the returned triangle is a true nearest one.
        EXPECT_GT(brute.dist2, kInside2) << fmt::format("{} is in triangle {}", s, brute.triangle);
        EXPECT_NEAR(std::sqrt(own2), std::sqrt(brute.dist2), 1e-7)
            << fmt::format("{}: grid triangle {} vs brute {}", s, loc.triangle, brute.triangle);
        EXPECT_NEAR(loc.distance, std::sqrt(brute.dist2), 1e-6);
        const Vec2d nearest = Interpolate(grid.uv, grid.triangles[loc.triangle], loc.barycentric);
        EXPECT_LT(Length(nearest - D(loc.nearest_uv)), 1e-6);
        EXPECT_NEAR(Length(u - nearest), std::sqrt(brute.dist2), 1e-6);
    }
    return virtual_count;
}

std::vector<Vec2f> RandomPoints(int count, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<Vec2f> p(count);
    for (Vec2f& q : p)
        q = Vec2f(u(rng), u(rng));
    return p;
}

TEST(ChartGrid, RealPointsLocateTheirTriangle) {
    const TriMesh m = GridPatch(33, 1, Cap);
    const ChartParam p = ParameterizeChart(m);
    ASSERT_EQ(p.status, ParamStatus::kOk) << p.message;
    const ChartGrid grid =
        BuildChartGrid(p.uv, m.triangles, DefaultGridResolution(m.triangle_count()));
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(0.02, 1);
    for (uint32_t t = 0; t < m.triangle_count(); ++t) {
        for (int k = 0; k < 3; ++k) {
            double b0 = u(rng), b1 = u(rng), b2 = u(rng);
            const double sum = b0 + b1 + b2;
            const auto& f = m.triangles[t];
            const Vec2d q = D(p.uv[f[0]]) * (b0 / sum) + D(p.uv[f[1]]) * (b1 / sum) +
                            D(p.uv[f[2]]) * (b2 / sum);
            const Vec2f qf(float(q.x), float(q.y));
            const GridLocation loc = grid.Locate(qf);
            ASSERT_TRUE(loc.real) << fmt::format("triangle {} point {}", t, qf);
            EXPECT_EQ(loc.triangle, t);
            EXPECT_NEAR(loc.barycentric[0] + loc.barycentric[1] + loc.barycentric[2], 1.0, 1e-6);
            EXPECT_LT(Length(Interpolate(p.uv, f, loc.barycentric) - D(qf)), 1e-6);
            EXPECT_EQ(loc.distance, 0.f);
        }
    }
    // Vertices and edge midpoints (shared by several triangles) are real too.
    for (const auto& f : m.triangles) {
        for (int k = 0; k < 3; ++k) {
            const Vec2f mid = (p.uv[f[k]] + p.uv[f[(k + 1) % 3]]) * 0.5f;
            EXPECT_TRUE(grid.Locate(p.uv[f[k]]).real);
            EXPECT_TRUE(grid.Locate(mid).real);
        }
    }
}

TEST(ChartGrid, VirtualPointsGetTheTrueNearestTriangle) {
    const TriMesh m = GridPatch(33, 3, Cap);
    const ChartParam p = ParameterizeChart(m);
    ASSERT_TRUE(HasUv(p.status));
    const ChartGrid grid =
        BuildChartGrid(p.uv, m.triangles, DefaultGridResolution(m.triangle_count()));
    const int virtual_count = CheckAgainstBruteForce(grid, RandomPoints(4000, 4));
    EXPECT_GT(virtual_count, 500);  // the cap leaves ~1/3 of the square virtual
    // The square's corners and edges, the farthest virtual points.
    CheckAgainstBruteForce(grid, {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {0.5f, 0}, {0, 0.5f}});
}

TEST(ChartGrid, ConcaveChartAndAnyResolution) {
    // A U-shaped flat chart (a notch cut from one side) mapped to uv by its own x, y: in
    // the notch the nearest triangle switches between the two arms.
    const TriMesh m = GridPatch(
        25, 5, [](double x, double y) { return Vec3d(x, y, 0); },
        [](int i, int j) { return !(i >= 8 && i < 16 && j >= 6); });
    std::vector<Vec2f> uv;
    for (const Vec3f& q : m.position)
        uv.push_back(Vec2f(0.1f + 0.8f * q.x, 0.15f + 0.7f * q.y));
    const std::vector<Vec2f> samples = RandomPoints(3000, 6);
    std::vector<GridLocation> first;
    for (const int resolution : {1, 3, 17, 35, 200}) {
        const ChartGrid grid = BuildChartGrid(uv, m.triangles, resolution);
        const int virtual_count = CheckAgainstBruteForce(grid, samples);
        EXPECT_GT(virtual_count, 1000);
        // Every resolution answers the same.
        std::vector<GridLocation> locs;
        for (const Vec2f& s : samples)
            locs.push_back(grid.Locate(s));
        if (first.empty()) {
            first = locs;
            continue;
        }
        for (size_t i = 0; i < locs.size(); ++i) {
            EXPECT_EQ(locs[i].real, first[i].real);
            EXPECT_NEAR(locs[i].distance, first[i].distance, 1e-6);
        }
    }
}

// 60 small random triangles, sharing no edge: either orientation, overlapping, every
// tenth degenerate.
void TriangleSoup(uint32_t seed, std::vector<Vec2f>* uv, Tris* tris) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.1f, 0.9f), d(-0.08f, 0.08f);
    for (uint32_t t = 0; t < 60; ++t) {
        const Vec2f c(u(rng), u(rng));
        uv->push_back(c + Vec2f(d(rng), d(rng)));
        uv->push_back(c + Vec2f(d(rng), d(rng)));
        uv->push_back(t % 10 == 0 ? uv->back() : c + Vec2f(d(rng), d(rng)));
        tris->push_back({3 * t, 3 * t + 1, 3 * t + 2});
    }
}

TEST(ChartGrid, TriangleSoupWithFlippedAndDegenerateTriangles) {
    std::vector<Vec2f> uv;
    Tris tris;
    TriangleSoup(7, &uv, &tris);
    const ChartGrid grid = BuildChartGrid(uv, tris, 12);
    EXPECT_EQ(grid.outline_tris.size(), tris.size());  // no shared edges: all outline
    CheckAgainstBruteForce(grid, RandomPoints(3000, 8));
}

// The virtual part as it was computed before the candidates were visited nearest box
// first (chart_grid.cpp at ac3f9c9): every candidate of u's cell in ascending order, the
// first strictly nearer one kept. Its arithmetic is the grid's own, copied.
struct PlainNearest {
    uint32_t triangle = kNoTriangle;
    double b[3] = {1, 0, 0};
    Vec2d nearest;
    double dist2 = INFINITY;
};

PlainNearest PlainVirtualScan(const ChartGrid& g, Vec2f s) {
    const Vec2d u(std::clamp(double(s.x), 0.0, 1.0), std::clamp(double(s.y), 0.0, 1.0));
    const int res = g.resolution;
    const size_t cell = size_t(std::min(int(u.y * res), res - 1)) * res +
                        size_t(std::min(int(u.x * res), res - 1));
    const uint32_t* begin = g.near_tris.data() + g.near_start[cell];
    const uint32_t* end = g.near_tris.data() + g.near_start[cell + 1];
    if (begin == end) {
        begin = g.outline_tris.data();
        end = begin + g.outline_tris.size();
    }
    PlainNearest r;
    for (const uint32_t* t = begin; t != end; ++t) {
        Vec2d p[3];
        for (int k = 0; k < 3; ++k)
            p[k] = D(g.uv[g.triangles[*t][k]]);
        double dist2 = INFINITY, b[3] = {1, 0, 0};
        Vec2d point;
        const double area = Cross(p[1] - p[0], p[2] - p[0]);
        bool inside = false;
        if (area != 0 && std::isfinite(area)) {
            b[0] = Cross(p[1] - u, p[2] - u) / area;
            b[1] = Cross(p[2] - u, p[0] - u) / area;
            b[2] = 1 - b[0] - b[1];
            inside = b[0] >= 0 && b[1] >= 0 && b[2] >= 0;
        }
        if (inside) {
            dist2 = 0;
            point = u;
        } else {
            b[0] = 1, b[1] = 0, b[2] = 0;
            for (int k = 0; k < 3; ++k) {
                const Vec2d& a = p[k];
                const Vec2d e = p[(k + 1) % 3] - a;
                const double len2 = Dot(e, e);
                const double f = len2 > 0 ? std::clamp(Dot(u - a, e) / len2, 0.0, 1.0) : 0.0;
                const Vec2d q = a + e * f;
                const double d2 = Dot(u - q, u - q);
                if (d2 < dist2) {
                    dist2 = d2;
                    b[k] = 1 - f;
                    b[(k + 1) % 3] = f;
                    b[(k + 2) % 3] = 0;
                    point = q;
                }
            }
        }
        if (dist2 < r.dist2) {
            r.dist2 = dist2;
            r.triangle = *t;
            std::copy(b, b + 3, r.b);
            r.nearest = point;
        }
    }
    return r;
}

// Locate's virtual answers are the plain scan's to the bit: the same triangle among
// equally near ones (a virtual point beyond an outline vertex is as near to every
// triangle at it), the same barycentrics, nearest point and distance. Charts with a notch,
// a soup with flipped and degenerate triangles; random points and a lattice through the
// outline's vertices.
TEST(ChartGrid, VirtualPointsGiveThePlainScansBits) {
    const TriMesh notch = GridPatch(
        25, 5, [](double x, double y) { return Vec3d(x, y, 0); },
        [](int i, int j) { return !(i >= 8 && i < 16 && j >= 6); });
    std::vector<Vec2f> notch_uv;
    for (const Vec3f& q : notch.position)
        notch_uv.push_back(Vec2f(0.1f + 0.8f * q.x, 0.15f + 0.7f * q.y));
    std::vector<Vec2f> soup_uv;
    Tris soup;
    TriangleSoup(21, &soup_uv, &soup);
    const TriMesh cap = GridPatch(17, 3, Cap);
    const ChartParam cap_param = ParameterizeChart(cap);
    ASSERT_TRUE(HasUv(cap_param.status));
    std::vector<Vec2f> points = RandomPoints(3000, 22);
    for (int j = 0; j <= 64; ++j)  // a lattice: rows of texel centres hit vertices' rows
        for (int i = 0; i <= 64; ++i)
            points.push_back(Vec2f(float(i) / 64, float(j) / 64));
    int virtual_count = 0, tied = 0;
    for (const auto& [uv, tris, resolution] :
         {std::tuple{notch_uv, notch.triangles, 17}, std::tuple{notch_uv, notch.triangles, 1},
          std::tuple{soup_uv, soup, 12},
          std::tuple{cap_param.uv, cap.triangles, DefaultGridResolution(cap.triangle_count())}}) {
        const ChartGrid grid = BuildChartGrid(uv, tris, resolution);
        for (const Vec2f& s : points) {
            const GridLocation got = grid.Locate(s);
            if (got.real)
                continue;
            ++virtual_count;
            const PlainNearest want = PlainVirtualScan(grid, s);
            ASSERT_EQ(got.triangle, want.triangle) << s.x << " " << s.y;
            for (int k = 0; k < 3; ++k)
                ASSERT_EQ(std::bit_cast<uint32_t>(got.barycentric[k]),
                          std::bit_cast<uint32_t>(float(want.b[k])));
            ASSERT_EQ(std::bit_cast<uint32_t>(got.nearest_uv.x),
                      std::bit_cast<uint32_t>(float(want.nearest.x)));
            ASSERT_EQ(std::bit_cast<uint32_t>(got.nearest_uv.y),
                      std::bit_cast<uint32_t>(float(want.nearest.y)));
            ASSERT_EQ(std::bit_cast<uint32_t>(got.distance),
                      std::bit_cast<uint32_t>(float(std::sqrt(want.dist2))));
            // A tie: another outline triangle as near as the answer.
            for (uint32_t t : grid.outline_tris)
                if (t != got.triangle && TriDist2(grid.uv, grid.triangles[t], D(s)) ==
                                             TriDist2(grid.uv, grid.triangles[got.triangle], D(s))) {
                    ++tied;
                    break;
                }
        }
    }
    EXPECT_GT(virtual_count, 3000);
    EXPECT_GT(tied, 100);  // ties were met: the lowest index must win them
}

TEST(ChartGrid, EmptyGrid) {
    const ChartGrid grid = BuildChartGrid({}, {}, 4);
    const GridLocation loc = grid.Locate({0.5f, 0.5f});
    EXPECT_EQ(loc.triangle, kNoTriangle);
    EXPECT_FALSE(loc.real);
}

TEST(ChartGrid, BuildIsDeterministic) {
    const TriMesh m = GridPatch(21, 9, Cap);
    const ChartParam p = ParameterizeChart(m);
    const ChartGrid a = BuildChartGrid(p.uv, m.triangles, 20);
    const ChartGrid b = BuildChartGrid(p.uv, m.triangles, 20);
    EXPECT_EQ(a.cell_start, b.cell_start);
    EXPECT_EQ(a.cell_tris, b.cell_tris);
    EXPECT_EQ(a.near_start, b.near_start);
    EXPECT_EQ(a.near_tris, b.near_tris);
    EXPECT_GT(a.MemoryBytes(), 0u);
}

TEST(ChartGridEvaluate, FlatChartExtrapolatesIsometrically) {
    // A tilted plane: the virtual part continues the plane, and since the map is an
    // isometry, 3D distance from the visibility point is s times the uv distance.
    const Vec3d o(0.3, 0.1, -0.2), e1 = Normalize(Vec3d(1, 0.2, 0.4));
    const Vec3d e2 = Normalize(Cross(Vec3d(0.1, 0.3, 1), e1)), n = Normalize(Cross(e1, e2));
    const TriMesh m = GridPatch(21, 10, [&](double x, double y) {
        return o + e1 * (1.5 * x) + e2 * (0.9 * y + 0.2 * x * x);
    });
    const ChartParam p = ParameterizeChart(m);
    ASSERT_EQ(p.status, ParamStatus::kOk) << p.message;
    const std::vector<Vec3f> normals = VertexNormals(m.position, m.triangles);
    const ChartGrid grid = BuildChartGrid(p.uv, m.triangles, 24);
    int virtual_count = 0;
    for (const Vec2f& s : RandomPoints(2000, 11)) {
        const SurfacePoint sp = Evaluate(grid, m.position, normals, s);
        ASSERT_NE(sp.triangle, kNoTriangle);
        EXPECT_NEAR(Dot(Vec3d(sp.position) - o, n), 0, 1e-5);
        EXPECT_NEAR(std::abs(Dot(Vec3d(sp.normal), n)), 1, 1e-5);
        if (sp.real) {
            EXPECT_TRUE(sp.position == sp.visible_position);
            continue;
        }
        ++virtual_count;
        const GridLocation loc = grid.Locate(s);
        const double d3 = Length(Vec3d(sp.position) - Vec3d(sp.visible_position));
        EXPECT_NEAR(d3, p.scale * loc.distance, 1e-4 * p.scale);
    }
    EXPECT_GT(virtual_count, 300);
}

TEST(ChartGridEvaluate, ContinuousAcrossTheBoundary) {
    const TriMesh m = GridPatch(25, 12, Cap);
    const ChartParam p = ParameterizeChart(m);
    ASSERT_EQ(p.status, ParamStatus::kOk);
    const std::vector<Vec3f> normals = VertexNormals(m.position, m.triangles);
    const ChartGrid grid = BuildChartGrid(p.uv, m.triangles, 30);
    const DiscCheck disc = CheckDisc(uint32_t(m.vertex_count()), m.triangles);
    ASSERT_EQ(disc.status, ParamStatus::kOk);
    const float eps = 2e-4f;
    int checked = 0;
    for (size_t k = 0; k < disc.boundary.size(); ++k) {
        const Vec2f a = p.uv[disc.boundary[k]],
                    b = p.uv[disc.boundary[(k + 1) % disc.boundary.size()]];
        const Vec2f mid = (a + b) * 0.5f, e = b - a;
        const float len = Length(e);
        // The boundary runs counter-clockwise around the chart: outside is on the right.
        const Vec2f out(e.y / len, -e.x / len);
        const SurfacePoint inside = Evaluate(grid, m.position, normals, mid - out * eps);
        const SurfacePoint outside = Evaluate(grid, m.position, normals, mid + out * eps);
        const SurfacePoint on = Evaluate(grid, m.position, normals, mid);
        if (!inside.real || outside.real)
            continue;  // a concave corner; skip
        ++checked;
        const double jump = Length(Vec3d(outside.position) - Vec3d(inside.position));
        EXPECT_LT(jump, 3 * eps * p.scale) << k;
        EXPECT_LT(Length(Vec3d(outside.visible_position) - Vec3d(on.position)), 1e-4 * p.scale);
        // Normals: the outside uses the triangle normal, close to the inside's.
        EXPECT_GT(Dot(Vec3d(outside.normal), Vec3d(inside.normal)), 0.95);
    }
    EXPECT_GT(checked, int(disc.boundary.size()) / 2);
}

TEST(ChartGridEvaluate, VertexNormalsOfACap) {
    const TriMesh m = GridPatch(15, 13, Cap);
    const std::vector<Vec3f> normals = VertexNormals(m.position, m.triangles);
    ASSERT_EQ(normals.size(), m.vertex_count());
    for (size_t v = 0; v < normals.size(); ++v) {
        // On the unit sphere the normal is the position; facets make it approximate.
        EXPECT_NEAR(Length(Vec3d(normals[v])), 1, 1e-5);
        EXPECT_GT(Dot(Vec3d(normals[v]), Vec3d(m.position[v])), 0.99);
    }
}

}  // namespace
}  // namespace mebake::stream

namespace mebake::stream {
namespace {

TEST(ChartGrid, InsideTriangleAgreesWithLocate) {
    // Random points over the whole square, and points on the chart's edges and vertices
    // (the tolerance band): InsideTriangle is Locate's answer for real points, none else,
    // and LocateReal is Locate's whole location (bit for bit) for real points, none else.
    const TriMesh m = GridPatch(33, 5, Cap, [](int i, int j) { return !(i > 10 && j < 8); });
    const ChartParam p = ParameterizeChart(m);
    ASSERT_TRUE(HasUv(p.status)) << p.message;
    const ChartGrid grid =
        BuildChartGrid(p.uv, m.triangles, DefaultGridResolution(m.triangle_count()));
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-0.01f, 1.01f);
    std::vector<Vec2f> points;
    for (int k = 0; k < 20000; ++k)
        points.push_back(Vec2f(u(rng), u(rng)));
    for (const Vec2f& q : p.uv)
        points.push_back(q);
    size_t real = 0;
    for (const Vec2f& q : points) {
        const GridLocation loc = grid.Locate(q);
        const uint32_t inside = grid.InsideTriangle(q);
        EXPECT_EQ(inside, loc.real ? loc.triangle : kNoTriangle) << q.x << " " << q.y;
        const GridLocation own = grid.LocateReal(q);
        EXPECT_EQ(own.real, loc.real);
        if (loc.real) {
            EXPECT_EQ(own.triangle, loc.triangle);
            EXPECT_EQ(std::memcmp(&own.barycentric, &loc.barycentric, sizeof loc.barycentric), 0);
            EXPECT_EQ(std::memcmp(&own.nearest_uv, &loc.nearest_uv, sizeof loc.nearest_uv), 0);
            EXPECT_EQ(std::bit_cast<uint32_t>(own.distance), std::bit_cast<uint32_t>(loc.distance));
        } else {
            EXPECT_EQ(own.triangle, kNoTriangle);
        }
        real += loc.real;
    }
    EXPECT_GT(real, 5000u);
    EXPECT_LT(real, points.size());
    EXPECT_EQ(ChartGrid{}.InsideTriangle(Vec2f(0.5f, 0.5f)), kNoTriangle);
    EXPECT_EQ(ChartGrid{}.LocateReal(Vec2f(0.5f, 0.5f)).triangle, kNoTriangle);
}

TEST(ChartGrid, PointsJustOutsideAnEdgeAreRealWithinTheTolerance) {
    // A square of two triangles with its right edge on x = 0.75: points k * 2^-24 (a float
    // ulp there) to its right are real (on the edge) up to the 2^-22 tolerance, k <= 4,
    // and virtual beyond, whichever cell holds them (grids of 1 to 64 cells a side).
    const std::vector<Vec2f> uv = {{0.25f, 0.25f}, {0.75f, 0.25f}, {0.75f, 0.75f}, {0.25f, 0.75f}};
    const Tris tris = {{0, 1, 2}, {0, 2, 3}};
    for (int res : {1, 3, 8, 64}) {
        const ChartGrid grid = BuildChartGrid(uv, tris, res);
        for (float y : {0.3f, 0.5f, 0.7f}) {
            for (int k = 1; k <= 12; ++k) {
                const Vec2f q(0.75f + float(k) * 0x1p-24f, y);
                const GridLocation loc = grid.Locate(q);
                EXPECT_EQ(loc.real, k <= 4) << res << " " << y << " " << k;
                EXPECT_EQ(grid.InsideTriangle(q), k <= 4 ? 0u : kNoTriangle) << res << " " << k;
                EXPECT_EQ(loc.triangle, 0u);
                if (!loc.real) {
                    EXPECT_NEAR(loc.distance, float(k) * 0x1p-24f, 1e-9f);
                }
            }
        }
    }
}

}  // namespace
}  // namespace mebake::stream
