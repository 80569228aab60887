// Penumbrae of a straight occluder edge at angles that run along no row of the light's cell
// grid, against the exact answer: the part of the light on the visible side of the plane
// through the receiver and the edge, in closed form. These are the penumbrae whose finest
// cells are counted 1/4 or 3/4 visible without rays (direct.cpp); the edge parallel to the
// grid is solver_test's square occluder.
#include "solve/direct.h"
#include "solve/penumbra_grid.h"
#include "solve/polygon_light.h"
#include "solve/rays.h"
#include "solve/visibility.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <utility>

namespace mebake::solve {
namespace {

struct EdgeScene {
    Scene scene;
    VisibilityScene vis;
    PolygonLight light;
    Vec3d e0, d, n;  // the occluder's edge (at y = 1) through e0 along d; it covers the n side
    explicit EdgeScene(double degrees) {
        light.vertices = {{-0.5, 2, -0.5}, {0.5, 2, -0.5}, {0.5, 2, 0.5}, {-0.5, 2, 0.5}};
        light.radiance = {1, 1, 1};
        scene.lights.push_back(light);
        const double a = degrees * std::numbers::pi / 180;
        e0 = Vec3d(0.05, 1, -0.03);
        d = Vec3d(std::cos(a), 0, std::sin(a));
        n = Vec3d(-std::sin(a), 0, std::cos(a));
        const Vec3d c[4] = {e0 - d * 10, e0 + d * 10, e0 + d * 10 + n * 10, e0 - d * 10 + n * 10};
        std::vector<float> occ;
        for (const auto& p : c)
            occ.insert(occ.end(), {float(p.x), float(p.y), float(p.z)});
        std::vector<uint32_t> tris = {0, 1, 2, 0, 2, 3};
        vis.AddTriangles(occ, tris, "occluder");
        vis.Commit();
    }
    // Irradiance on an upward floor at p from the light's visible part.
    double Exact(const Vec3d& p) const {
        Vec3d m = Normalize(Cross(d, e0 - p));
        if (Dot(e0 + n - p, m) > 0)
            m = m * -1.0;  // keep the side away from the occluder
        auto visible = ClipToHalfSpace(light.vertices, p, m);
        return visible.size() >= 3 ? IrradianceClipped(visible, 1.0, p, Vec3d(0, 1, 0)) : 0.0;
    }
};

TEST(Penumbra, GenericEdgeAnglesCloseToExact) {
    for (double degrees : {13.0, 27.0, 58.0, 101.0, 152.0}) {
        EdgeScene s(degrees);
        DirectLight direct(s.scene, s.scene.solver, s.vis, 1e-4f, 10);
        std::vector<ReceiverPoint> pts;
        // Across the penumbra (its width on the floor is about the light's, 1), at y = 0.
        for (double t = -1.2; t <= 1.2; t += 0.04) {
            const Vec3d p = Vec3d(s.e0.x, 0, s.e0.z) + s.n * t + s.d * 0.11;
            pts.push_back({Vec3f(p), {0, 1, 0}, Vec3f(p), {0, 1, 0}});
        }
        std::vector<float> e(pts.size() * 9);
        const uint64_t rays0 = RaysByKind()[size_t(RayKind::kPenumbra)];
        direct.Evaluate(pts, e);
        const uint64_t rays = RaysByKind()[size_t(RayKind::kPenumbra)] - rays0;
        const double lit = IrradianceClipped(s.light.vertices, 1.0, Vec3d(0, 0, 0), Vec3d(0, 1, 0));
        double worst = 0, sum2 = 0;
        int in_penumbra = 0;
        for (size_t p = 0; p < pts.size(); ++p) {
            const double exact = s.Exact(Vec3d(pts[p].position));
            const double err = std::abs(e[p * 9 + 1] - exact) / lit;
            worst = std::max(worst, err);
            sum2 += err * err;
            in_penumbra += exact > 0.01 * lit && exact < 0.99 * lit;
        }
        const double rms = std::sqrt(sum2 / double(pts.size()));
        // Default 64 samples (8 x 8 cells per fan triangle, a finest cell is 1/128 of the
        // light): one straight edge crosses ~16 finest cells. Measured: worst 1.3-2.8 %, rms
        // 0.30-0.84 % (one ray per finest mixed cell, before session 3: worst 1.3-2.4 %, rms
        // 0.42-0.70 %, with 26-37 rays per penumbra point instead of 18-26).
        EXPECT_LT(worst, 0.035) << degrees << " degrees";
        EXPECT_LT(rms, 0.01) << degrees << " degrees";
        ASSERT_GT(in_penumbra, 10) << "the points must cross the penumbra";
        // Only cell corners are traced: fewer rays than 64 per penumbra point.
        EXPECT_LT(rays, uint64_t(40 * in_penumbra)) << degrees << " degrees";
        std::printf("edge at %5.1f deg: worst %.3f %%, rms %.3f %% of the lit value, %.1f rays per "
                    "penumbra point\n",
                    degrees, 100 * worst, 100 * rms, double(rays) / in_penumbra);
    }
}

// Points on the lit side of the penumbra, where a sliver to half of the light is hidden:
// most of their cells are visible, and their shared edges cancel, so E is summed over the
// visible part's outline and the finest cells (PenumbraPass::Sum). It must agree with the
// exact answer as elsewhere (GenericEdgeAnglesCloseToExact: 3.5 % of the lit value at
// worst), and the hidden part must come off: well under the unoccluded value wherever a
// tenth of it is hidden.
TEST(Penumbra, MostlyVisibleLightLosesItsHiddenPart) {
    EdgeScene s(27.0);
    DirectLight direct(s.scene, s.scene.solver, s.vis, 1e-4f, 10);
    std::vector<ReceiverPoint> pts;
    for (double t = -1.0; t <= 0.0; t += 0.05) {
        const Vec3d p = Vec3d(s.e0.x, 0, s.e0.z) + s.n * t;
        pts.push_back({Vec3f(p), {0, 1, 0}, Vec3f(p), {0, 1, 0}});
    }
    std::vector<float> e(pts.size() * 9);
    direct.Evaluate(pts, e);
    const double lit = IrradianceClipped(s.light.vertices, 1.0, Vec3d(0, 0, 0), Vec3d(0, 1, 0));
    int partly = 0;
    for (size_t p = 0; p < pts.size(); ++p) {
        const Vec3d x(pts[p].position);
        const double exact = s.Exact(x), full = IrradianceClipped(s.light.vertices, 1.0, x, {0, 1, 0});
        EXPECT_NEAR(e[p * 9 + 1], exact, 0.035 * lit) << "t = " << -1.0 + 0.05 * double(p);
        if (full - exact > 0.1 * full) {
            ++partly;
            EXPECT_LT(e[p * 9 + 1], full - 0.5 * (full - exact)) << "t = " << -1.0 + 0.05 * double(p);
        }
    }
    EXPECT_GT(partly, 3);
}

// Tilted receivers whose horizon cuts the light: the cells it crosses are clipped and
// summed on their own, the others through their shared edges (PenumbraPass::Sum). The sum
// must agree with the exact answer (the visible part above the horizon) as on a flat floor,
// and miss none of the horizon's cut: wherever a tenth of the unoccluded light is below the
// horizon, E is well under the unclipped light.
TEST(Penumbra, HorizonCuttingTheLightCloseToExact) {
    for (double degrees : {27.0, 101.0}) {
        EdgeScene s(degrees);
        DirectLight direct(s.scene, s.scene.solver, s.vis, 1e-4f, 10);
        const Vec3d h = Normalize(s.d + Vec3d(0, 0.1, 0));  // leaning along the edge
        std::vector<ReceiverPoint> pts;
        for (double t = -1.2; t <= 1.2; t += 0.04) {
            const Vec3d p = Vec3d(s.e0.x, 0, s.e0.z) + s.n * t + s.d * 0.11;
            pts.push_back({Vec3f(p), Vec3f(h), Vec3f(p), Vec3f(h)});
        }
        std::vector<float> e(pts.size() * 9);
        direct.Evaluate(pts, e);
        const double lit = IrradianceClipped(s.light.vertices, 1.0, Vec3d(0, 0, 0), h);
        int in_penumbra = 0, cut = 0;
        for (size_t p = 0; p < pts.size(); ++p) {
            const Vec3d x(pts[p].position);
            Vec3d m = Normalize(Cross(s.d, s.e0 - x));
            if (Dot(s.e0 + s.n - x, m) > 0)
                m = m * -1.0;
            const auto visible = ClipToHalfSpace(s.light.vertices, x, m);
            const double exact = visible.size() >= 3 ? IrradianceClipped(visible, 1.0, x, h) : 0.0;
            const double got = Dot(Vec3d(e[p * 9], e[p * 9 + 1], e[p * 9 + 2]), h);
            EXPECT_NEAR(got, exact, 0.035 * lit) << degrees << " degrees, point " << p;
            in_penumbra += exact > 0.01 * lit && exact < 0.99 * lit;
            // Unclipped, the visible light below the horizon would count negative.
            const double unclipped =
                visible.size() >= 3 ? Dot(VectorIrradiance(visible, 1.0, x), h) : 0.0;
            if (exact - unclipped > 0.05 * lit) {
                cut += exact > 0.01 * lit && exact < 0.99 * lit;
                EXPECT_GT(got, unclipped + 0.5 * (exact - unclipped)) << degrees << " degrees";
            }
        }
        EXPECT_GT(in_penumbra, 10) << degrees << " degrees";
        EXPECT_GT(cut, 5) << degrees << " degrees";  // of them, cut by the horizon
        std::printf("edge at %5.1f deg: %d penumbra points, %d cut by the horizon\n", degrees,
                    in_penumbra, cut);
    }
}

// The light's centre is a classification target, and on a parallelogram also the grid
// vertex in the middle of the fan triangles' shared diagonal: the same segment from the
// same origin. A point that sees the whole light but its centre (a small occluder in
// between) is in penumbra; its grid takes the centre's state from the classification ray:
// at the coarse level only the four edge midpoints are traced (before session 19 the
// centre again: 5); at each of the next two levels the six cells around the centre are the
// only mixed ones and their 12 new vertices are traced (7 per fan triangle, 2 of them on
// the shared diagonal). The finest cells around it count a quarter hidden without a ray.
TEST(Penumbra, LightCentreTakesItsClassificationRay) {
    Scene scene;
    PolygonLight light;
    light.vertices = {{-0.5, 2, -0.5}, {0.5, 2, -0.5}, {0.5, 2, 0.5}, {-0.5, 2, 0.5}};
    light.radiance = {1, 1, 1};
    scene.lights.push_back(light);
    VisibilityScene vis;
    const float h = 0.02f;  // hides the centre from the origin, no other grid vertex
    std::vector<float> occ = {-h, 1, -h, h, 1, -h, h, 1, h, -h, 1, h};
    std::vector<uint32_t> tris = {0, 1, 2, 0, 2, 3};
    vis.AddTriangles(occ, tris, "occluder");
    vis.Commit();
    DirectLight direct(scene, scene.solver, vis, 1e-4f, 10);
    const std::vector<ReceiverPoint> pts = {{{0, 0, 0}, {0, 1, 0}, {0, 0, 0}, {0, 1, 0}}};
    std::vector<float> e(9);
    const auto before = RaysByKind();
    direct.Evaluate(pts, e, DirectLight::kLights);
    const auto after = RaysByKind();
    EXPECT_EQ(after[size_t(RayKind::kClassify)] - before[size_t(RayKind::kClassify)], 5u);
    const uint64_t penumbra =
        after[size_t(RayKind::kPenumbra)] - before[size_t(RayKind::kPenumbra)];
    EXPECT_EQ(penumbra, 4u + 12u + 12u);
    // Lit but for the finest cells around the centre, a quarter each of their 6 / 128.
    const double lit = IrradianceClipped(light.vertices, 1.0, Vec3d(0, 0, 0), Vec3d(0, 1, 0));
    EXPECT_LT(e[1], lit);
    EXPECT_GT(e[1], 0.97 * lit);
}

// Every cell the penumbra's refinement can make (the coarse level's and all their
// descendants, penumbra.cpp): two cell edges share an edge slot exactly when their ends
// have the same two vertex indices, on lights of 3 to 7 vertices (the shared diagonals
// between fan triangles, v0's own index in fan triangles 2 and up) and grids of 1 to 32.
TEST(PenumbraGrid, EdgeSlotsNameTheVertexPairs) {
    for (size_t nt = 1; nt <= 5; ++nt) {
        for (int g = 1; g <= 32; g *= 2) {
            const PenumbraGrid grid{g, nt};
            std::map<uint32_t, std::pair<size_t, size_t>> pair_of;
            std::map<std::pair<size_t, size_t>, uint32_t> slot_of;
            size_t cells = 0;
            using Cell = std::array<int, 6>;  // a0 b0 a1 b1 a2 b2
            for (size_t t = 0; t < nt; ++t) {
                std::vector<Cell> cur;
                const int s = g / std::min(g, 2);
                for (int b = 0; b < g; b += s) {
                    for (int a = 0; a + b < g; a += s) {
                        cur.push_back({a, b, a + s, b, a, b + s});
                        if (a + b + 2 * s <= g)
                            cur.push_back({a + s, b, a + s, b + s, a, b + s});
                    }
                }
                while (!cur.empty()) {
                    std::vector<Cell> next;
                    for (const Cell& c : cur) {
                        ++cells;
                        int side = 0;
                        for (int j = 0; j < 3; ++j) {
                            const int i = (j + 1) % 3;
                            const size_t u = grid.VertexIndex(t, c[2 * j], c[2 * j + 1]);
                            const size_t w = grid.VertexIndex(t, c[2 * i], c[2 * i + 1]);
                            const uint32_t slot =
                                grid.EdgeSlot(t, c[2 * j], c[2 * j + 1], c[2 * i], c[2 * i + 1]);
                            ASSERT_LT(slot, grid.EdgeSlots());
                            ASSERT_LT(std::max(u, w), grid.vertices());
                            const std::pair<size_t, size_t> key{std::min(u, w), std::max(u, w)};
                            const auto p = pair_of.insert({slot, key}).first;
                            EXPECT_EQ(p->second, key) << "nt " << nt << " g " << g << " t " << t;
                            const auto k = slot_of.insert({key, slot}).first;
                            EXPECT_EQ(k->second, slot) << "nt " << nt << " g " << g << " t " << t;
                            side = std::max({side, std::abs(c[2 * j] - c[2 * i]),
                                             std::abs(c[2 * j + 1] - c[2 * i + 1])});
                        }
                        if (side <= 1)
                            continue;
                        int m[6];
                        for (int j = 0; j < 3; ++j) {
                            const int i = (j + 1) % 3;
                            m[2 * j] = (c[2 * j] + c[2 * i]) / 2;
                            m[2 * j + 1] = (c[2 * j + 1] + c[2 * i + 1]) / 2;
                        }
                        next.push_back({c[0], c[1], m[0], m[1], m[4], m[5]});
                        next.push_back({m[0], m[1], c[2], c[3], m[2], m[3]});
                        next.push_back({m[4], m[5], m[2], m[3], c[4], c[5]});
                        next.push_back({m[0], m[1], m[2], m[3], m[4], m[5]});
                    }
                    cur.swap(next);
                }
            }
            // Each level's cells: g^2 at the finest, a third more above it.
            EXPECT_GE(cells, size_t(g) * size_t(g) * nt);
            EXPECT_EQ(pair_of.size(), slot_of.size());
        }
    }
}

}  // namespace
}  // namespace mebake::solve
