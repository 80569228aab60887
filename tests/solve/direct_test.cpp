// Direct light at points against closed forms: unoccluded lights, an occluder's penumbra
// (exact here: the light minus the occluder's central projection), the sky.
#include "solve/direct.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "solve/polygon_light.h"
#include "solve/visibility.h"

namespace mebake::solve {
namespace {

struct OccluderScene {
    Scene scene;
    VisibilityScene vis;
    PolygonLight light;
    OccluderScene(int samples) {
        light.vertices = {{-0.5, 2, -0.5}, {0.5, 2, -0.5}, {0.5, 2, 0.5}, {-0.5, 2, 0.5}};
        light.radiance = {1, 1, 1};
        scene.lights.push_back(light);
        scene.solver.light_samples = samples;
        std::vector<float> occ = {-0.4f, 1, -0.4f, 0.4f, 1, -0.4f, 0.4f, 1, 0.4f, -0.4f, 1, 0.4f};
        std::vector<uint32_t> tris = {0, 1, 2, 0, 2, 3};
        vis.AddTriangles(occ, tris, "occluder");
        vis.Commit();
    }
    double Exact(double x, double z) const {
        const Vec3d p(x, 0, z);
        double x0 = std::max(-0.5, x + 2 * (-0.4 - x)), x1 = std::min(0.5, x + 2 * (0.4 - x));
        double z0 = std::max(-0.5, z + 2 * (-0.4 - z)), z1 = std::min(0.5, z + 2 * (0.4 - z));
        double full = IrradianceClipped(light.vertices, 1.0, p, Vec3d(0, 1, 0));
        if (x0 >= x1 || z0 >= z1) return full;
        std::vector<Vec3d> hidden = {{x0, 2, z0}, {x1, 2, z0}, {x1, 2, z1}, {x0, 2, z1}};
        return full - IrradianceClipped(hidden, 1.0, p, Vec3d(0, 1, 0));
    }
};

TEST(DirectLight, PenumbraCloseToExact) {
    OccluderScene s(256);
    DirectLight direct(s.scene, s.scene.solver, s.vis, 1e-4f, 10);
    std::vector<ReceiverPoint> pts;
    for (double x = 0; x <= 2; x += 0.05) pts.push_back({Vec3f(float(x), 0, 0.1f), {0, 1, 0}, Vec3f(float(x), 0, 0.1f)});
    std::vector<float> e(pts.size() * 9);
    direct.Evaluate(pts, e);
    // Directly under the light, were the occluder not there.
    const double lit = IrradianceClipped(s.light.vertices, 1.0, Vec3d(0, 0, 0), Vec3d(0, 1, 0));
    for (size_t p = 0; p < pts.size(); ++p) {
        double got = e[p * 9 + 1];  // colour 0, y component = irradiance on the floor
        EXPECT_NEAR(got, s.Exact(pts[p].position.x, 0.1), 0.01 * lit) << "x = " << pts[p].position.x;
    }
}

// A uniform sky of this radiance about +y, and nothing else.
Scene SkyAlone(const Vec3d& radiance) {
    Scene scene;
    scene.sky.type = Sky::Type::Uniform;
    scene.sky.radiance = radiance;
    scene.sky.up = {0, 1, 0};
    return scene;
}

TEST(DirectLight, UniformSkyOnOpenPlane) {
    const Scene scene = SkyAlone({1, 2, 3});
    VisibilityScene vis;
    std::vector<float> far = {100, 100, 100, 101, 100, 100, 100, 101, 100};
    std::vector<uint32_t> tri = {0, 1, 2};
    vis.AddTriangles(far, tri, "far");
    vis.Commit();
    DirectLight direct(scene, scene.solver, vis, 1e-4f, 10);
    std::vector<ReceiverPoint> pts = {{{0, 0, 0}, {0, 1, 0}, {0, 0, 0}}};
    std::vector<float> e(9);
    direct.Evaluate(pts, e);
    // Unoccluded uniform sky over the upper hemisphere: E = pi L up.
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(e[size_t(3 * c + 1)], std::numbers::pi * (c + 1), 1e-3 * (c + 1));
    EXPECT_NEAR(e[0], 0, 0.05);
}


// The refinement's test for a shadow between a node's points: the light's centre hidden
// from some points and seen from others.
TEST(DirectLight, ShadowEdgeAmongPoints) {
    OccluderScene s(16);
    DirectLight direct(s.scene, s.scene.solver, s.vis, 1e-4f, 10);
    auto at = [](float x) { return ReceiverPoint{{x, 0, 0}, {0, 1, 0}, {x, 0, 0}}; };
    const std::vector<ReceiverPoint> across = {at(3), at(0), at(3.1f)};
    const std::vector<ReceiverPoint> lit = {at(3), at(3.1f)}, hidden = {at(0), at(0.1f)};
    EXPECT_TRUE(direct.ShadowEdgeAmong(across));
    EXPECT_FALSE(direct.ShadowEdgeAmong(lit));
    EXPECT_FALSE(direct.ShadowEdgeAmong(hidden));
}

// A visibility point a little under the surface (as the chord between geometry-image texels
// runs under a convex bend) must see the sky from the surface above it, not from below it;
// one deeper than the reach stays where it is and sees nothing.
TEST(DirectLight, VisibilityPointUnderTheSurfaceMovesOntoIt) {
    const Scene scene = SkyAlone({1, 1, 1});
    VisibilityScene vis;
    // A floor y = 0 facing up (counter-clockwise seen from above), wide enough that no sky
    // direction passes beside it from under it.
    std::vector<float> floor = {-1e4f, 0, -1e4f, -1e4f, 0, 1e4f, 1e4f, 0, 1e4f, 1e4f, 0, -1e4f};
    std::vector<uint32_t> tris = {0, 1, 2, 0, 2, 3};
    vis.AddTriangles(floor, tris, "floor");
    vis.Commit();
    const float offset = 1e-3f, reach = 0.05f;
    DirectLight direct(scene, scene.solver, vis, offset, 10, reach);
    auto sky_at = [&](float depth) {
        std::vector<ReceiverPoint> pts = {{{0, -depth, 0}, {0, 1, 0}, {0, -depth, 0}}};
        std::vector<float> e(9);
        direct.Evaluate(pts, e);
        return e[1];
    };
    EXPECT_NEAR(sky_at(0.02f), std::numbers::pi, 1e-3);   // under by 20 offsets: moved up
    EXPECT_NEAR(sky_at(0.f), std::numbers::pi, 1e-3);     // on it: unchanged
    EXPECT_NEAR(sky_at(0.2f), 0, 1e-6);                   // deeper than the reach: blocked
}

// A visibility point a little above the surface (as the chord between geometry-image texels
// floats over a concave bend) must take the light the surface below it gets, not pass over
// the rim that shades it: a floor with a wall 0.01 high at x = 0.05 and a light far to
// its side, low (3 degrees up at most): the floor at the origin is in the wall's umbra, a
// point 0.02 above it sees the whole light. One higher than the reach stays where it is.
TEST(DirectLight, VisibilityPointAboveTheSurfaceMovesOntoIt) {
    Scene scene;
    PolygonLight light;
    light.vertices = {{10, 0.4, -0.1}, {10, 0.4, 0.1}, {10, 0.6, 0.1}, {10, 0.6, -0.1}};
    light.radiance = {100, 100, 100};
    light.two_sided = true;
    scene.lights.push_back(light);
    VisibilityScene vis;
    std::vector<float> geo = {-1e4f, 0, -1e4f, -1e4f, 0, 1e4f, 1e4f, 0, 1e4f, 1e4f, 0, -1e4f,  // floor
                              0.05f, 0, -1e4f, 0.05f, 0, 1e4f, 0.05f, 0.01f, 1e4f, 0.05f, 0.01f, -1e4f};
    std::vector<uint32_t> tris = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
    vis.AddTriangles(geo, tris, "floor and wall");
    vis.Commit();
    const float offset = 1e-3f, reach = 0.05f;
    DirectLight direct(scene, scene.solver, vis, offset, 100, reach);
    auto light_at = [&](float height) {
        std::vector<ReceiverPoint> pts = {{{0, height, 0}, {0, 1, 0}, {0, height, 0}}};
        std::vector<float> e(9);
        direct.Evaluate(pts, e);
        return double(e[1]);
    };
    const double lit = IrradianceClipped(light.vertices, 100.0, Vec3d(0, 0.2, 0), Vec3d(0, 1, 0));
    ASSERT_GT(lit, 0);
    EXPECT_NEAR(light_at(0.f), 0, 1e-6);      // on the floor: in the wall's umbra
    EXPECT_NEAR(light_at(0.02f), 0, 1e-6);    // above by 20 offsets: moved down, in umbra
    EXPECT_NEAR(light_at(0.2f), lit, 0.02 * lit);  // higher than the reach: over the wall
}

}  // namespace
}  // namespace mebake::solve
