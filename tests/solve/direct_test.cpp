// Direct light at points against closed forms: unoccluded lights, an occluder's penumbra
// (exact here: the light minus the occluder's central projection), the sky.
#include "solve/direct.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>
#include <thread>

#include "solve/polygon_light.h"
#include "solve/rays.h"
#include "solve/sky.h"
#include "solve/thread_scratch.h"
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

// A scene with one small triangle far away: every sky direction from the origin is open.
void OpenSky(VisibilityScene& vis) {
    std::vector<float> far = {100, 100, 100, 101, 100, 100, 100, 101, 100};
    std::vector<uint32_t> tri = {0, 1, 2};
    vis.AddTriangles(far, tri, "far");
    vis.Commit();
}

// A square plane y = height, 2e4 wide, facing up (counter-clockwise seen from above).
void WidePlane(VisibilityScene& vis, float height, const char* name) {
    std::vector<float> v = {-1e4f, height, -1e4f, -1e4f, height, 1e4f,
                            1e4f,  height, 1e4f,  1e4f,  height, -1e4f};
    std::vector<uint32_t> tris = {0, 1, 2, 0, 2, 3};
    vis.AddTriangles(v, tris, name);
    vis.Commit();
}

TEST(DirectLight, UniformSkyOnOpenPlane) {
    const Scene scene = SkyAlone({1, 2, 3});
    VisibilityScene vis;
    OpenSky(vis);
    DirectLight direct(scene, scene.solver, vis, 1e-4f, 10);
    std::vector<ReceiverPoint> pts = {{{0, 0, 0}, {0, 1, 0}, {0, 0, 0}}};
    std::vector<float> e(9);
    direct.Evaluate(pts, e);
    // Unoccluded uniform sky over the upper hemisphere: E = pi L up.
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(e[size_t(3 * c + 1)], std::numbers::pi * (c + 1), 1e-3 * (c + 1));
    EXPECT_NEAR(e[0], 0, 0.05);
}

// A receiver tilted from the sky's up that sees its whole sky: E is the closed form over the
// directions above both horizons (the control variate), exact, where the fixed directions
// alone were off by up to 2 % of pi in a component and stepped as the tilt passed them.
TEST(DirectLight, OpenTiltedReceiverSeesItsSkyExactly) {
    const Scene scene = SkyAlone({1, 2, 3});
    VisibilityScene vis;
    OpenSky(vis);
    DirectLight direct(scene, scene.solver, vis, 1e-4f, 10);
    for (double deg : {10.0, 37.0, 80.0, 125.0}) {
        const double a = deg * std::numbers::pi / 180;
        const Vec3f n(float(std::sin(a)), float(std::cos(a)), 0.2f * float(std::sin(a)));
        const Vec3f nn = Normalize(n);
        std::vector<ReceiverPoint> pts = {{{0, 0, 0}, nn, {0, 0, 0}, nn}};
        std::vector<float> e(9);
        direct.Evaluate(pts, e);
        const std::vector<Vec3d> planes = {Vec3d{0, 1, 0}, Vec3d(nn)};
        const Vec3d want = HalfSpacesVector(planes);
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(e[size_t(3 * c + k)], want[k] * (c + 1), 1e-5 * (c + 1)) << deg;
    }
}

// EvaluateSky's prior: directions given as seen (or occluded) take no ray and count as such;
// the states it reports are what a point saw. Under a roof, the traced sky is dark; with
// every direction given as seen it is the open sky.
TEST(DirectLight, SkyPriorTakesDirectionsWithoutRays) {
    const Scene scene = SkyAlone({1, 1, 1});
    VisibilityScene vis;
    WidePlane(vis, 1, "roof");
    DirectLight direct(scene, scene.solver, vis, 1e-4f, 10);
    const Vec3f up{0, 1, 0};
    std::vector<ReceiverPoint> pts = {{{0, 0, 0}, up, {0, 0, 0}, up}};
    std::vector<float> e(9);
    std::vector<uint8_t> states;
    direct.EvaluateSky(pts, e, {}, &states);
    EXPECT_NEAR(e[1], 0, 1e-6);
    ASSERT_EQ(states.size(), direct.sky_direction_count());
    EXPECT_TRUE(std::all_of(states.begin(), states.end(), [](uint8_t s) { return s == 1; }));
    const std::vector<uint8_t> seen(direct.sky_direction_count(), 0);
    direct.EvaluateSky(pts, e, seen, &states);
    EXPECT_NEAR(e[1], std::numbers::pi, 1e-5);
    EXPECT_TRUE(std::all_of(states.begin(), states.end(), [](uint8_t s) { return s == 0; }));
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
    WidePlane(vis, 0, "floor");
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

// A small square light (side 0.2, radiance 100) 10 away, `elevation` degrees above the
// x-z plane toward +z (toward = 1) or -z (-1), facing the origin.
PolygonLight FarSquareLight(double elevation, double toward) {
    const double d = std::numbers::pi / 180;
    const double up = std::sin(elevation * d), ahead = toward * std::cos(elevation * d);
    const Vec3d c(0, 10 * up, 10 * ahead), a(1, 0, 0), b(0, ahead, -up);
    const double h = 0.1;
    PolygonLight light;
    light.vertices = {c - a * h - b * h, c - a * h + b * h, c + a * h + b * h, c + a * h - b * h};
    light.radiance = {100, 100, 100};
    light.two_sided = true;
    return light;
}

// A fold of large faces: the point's face is tilted 10 degrees from the smooth horizon the
// caller gives, and a small light sits 5 degrees above that horizon but 5 below the face's
// plane. The path tracer has it blocked by the surface itself (reference.cpp); the shadow
// rays, offset along the smooth normal, cross the face's plane beyond the ridge and escape.
struct FoldScene {
    Scene scene;
    VisibilityScene vis;
    PolygonLight light;
    Vec3f face_normal;
    FoldScene() {
        const double d = std::numbers::pi / 180;
        light = FarSquareLight(5, 1);
        scene.lights.push_back(light);
        // Face A: y = z tan(10 deg) up to the ridge at z = 0.005; face B falls away beyond
        // it; patch C lies flat, far to the side, and sees the light.
        const float t = float(std::tan(10 * d)), r = 0.005f;
        face_normal = Normalize(Vec3f(0, 1, -t));
        std::vector<float> geo = {-1, -t, -1, 1, -t, -1, 1, r * t, r, -1, r * t, r,  // A
                                  1, -1, 1, -1, -1, 1,                                // B
                                  4, 0, -1, 6, 0, -1, 6, 0, 1, 4, 0, 1};               // C
        std::vector<uint32_t> tris = {0, 2, 1, 0, 3, 2, 3, 4, 2, 3, 5, 4, 6, 8, 7, 6, 9, 8};
        vis.AddTriangles(geo, tris, "fold");
        vis.Commit();
    }
};

TEST(DirectLight, LightBelowThePointsFaceIsBlockedByIt) {
    FoldScene f;
    const float offset = 1e-3f, reach = 0.05f;
    DirectLight direct(f.scene, f.scene.solver, f.vis, offset, 100, reach);
    const Vec3f n(0, 1, 0);
    // The shadow ray from the offset origin crosses the face's plane beyond the ridge.
    const double d = std::numbers::pi / 180;
    const double cross_z = offset / (std::cos(5 * d) * std::tan(10 * d) - std::sin(5 * d)) * std::cos(5 * d);
    ASSERT_GT(cross_z, 0.005);
    std::vector<ReceiverPoint> on_fold = {{{0, 0, 0}, n, {0, 0, 0}, n}};
    std::vector<float> e(9);
    direct.Evaluate(on_fold, e, DirectLight::kLights);
    EXPECT_NEAR(e[1], 0.0, 1e-9);  // without the face plane: 0.0035, the full closed form
    std::vector<ReceiverPoint> on_flat = {{{5, 0, 0}, n, {5, 0, 0}, n}};
    direct.Evaluate(on_flat, e, DirectLight::kLights);
    const double lit = IrradianceClipped(f.light.vertices, 100.0, Vec3d(5, 0, 0), Vec3d(0, 1, 0));
    ASSERT_GT(lit, 0);
    EXPECT_NEAR(e[1], lit, 1e-3 * lit);
    // Without a horizon (visibility only) nothing changes: the ray escapes over the ridge.
    std::vector<ReceiverPoint> no_horizon = {{{0, 0, 0}, n, {0, 0, 0}}};
    direct.Evaluate(no_horizon, e, DirectLight::kLights);
    EXPECT_GT(e[1], 0.5 * lit);
    // The refinement sees the fold as an edge of the light: hidden on A, seen on C.
    std::vector<ReceiverPoint> both = {on_fold[0], on_flat[0]};
    EXPECT_TRUE(direct.ShadowEdgeAmong(both));
    EXPECT_FALSE(direct.ShadowEdgeAmong(on_flat));
}

// A visibility point a little under or over the fold's face A moves onto it along its
// normal, and takes A's plane from the ray that found it: the light below that plane is
// cut as with a face ray, and no face ray is traced (one origin ray under the face, the
// ray up; two over it, up then down).
TEST(DirectLight, PointMovedOntoAFaceTakesItsPlaneWithoutAFaceRay) {
    FoldScene f;
    const float offset = 1e-3f, reach = 0.05f;
    DirectLight direct(f.scene, f.scene.solver, f.vis, offset, 100, reach);
    const Vec3f n(0, 1, 0);
    for (const auto& [height, rays] : {std::pair{-0.002f, 1u}, std::pair{0.002f, 2u}}) {
        std::vector<ReceiverPoint> pts = {{{0, height, 0}, n, {0, height, 0}, n}};
        std::vector<float> e(9);
        const uint64_t before = RaysByKind()[size_t(RayKind::kOrigin)];
        direct.Evaluate(pts, e, DirectLight::kLights);
        EXPECT_EQ(RaysByKind()[size_t(RayKind::kOrigin)] - before, rays) << height;
        EXPECT_NEAR(e[1], 0.0, 1e-9) << height;  // cut by A's plane, as from its face ray
    }
}

// A patch of four probes (with their cache keys) and a centre on face C at height y.
void ProbePatch(float y, std::vector<ReceiverPoint>* pts, std::vector<ProbeKey>* keys) {
    const Vec3f n(0, 1, 0);
    for (const auto& [x, z] : {std::pair{4.5f, -0.5f}, {5.5f, -0.5f}, {4.5f, 0.5f}, {5.5f, 0.5f},
                               {5.f, 0.f}}) {
        pts->push_back({{x, y, z}, n, {x, y, z}, n});
        if (keys->size() < 4)
            keys->push_back({std::bit_cast<uint32_t>(x), std::bit_cast<uint32_t>(z), 0, 0});
    }
}

// Probes found in the cache take their E and states from it, so their visibility points
// are not moved onto the surface: a patch of four probes and a centre on patch C, a little
// under it (one origin ray each, up), evaluated twice with one cache traces five origin rays,
// then one (the centre's), and gives the same bits. With the light taken as known it is
// evaluated at the probes too, so they are moved again.
TEST(DirectLight, ProbesFoundInTheCacheAreNotMovedOntoTheSurface) {
    FoldScene f;
    DirectLight direct(f.scene, f.scene.solver, f.vis, 1e-3f, 100, 0.05f);
    std::vector<ReceiverPoint> pts;
    std::vector<ProbeKey> keys;
    ProbePatch(-0.002f, &pts, &keys);
    ProbeCache cache;
    auto origin_rays = [&](std::vector<float>* e, std::span<const uint8_t> known) {
        const uint64_t before = RaysByKind()[size_t(RayKind::kOrigin)];
        direct.Evaluate(pts, *e, DirectLight::kLights, 4, &cache, keys, known);
        return RaysByKind()[size_t(RayKind::kOrigin)] - before;
    };
    std::vector<float> first(pts.size() * 9), again(pts.size() * 9), known_e(pts.size() * 9);
    EXPECT_EQ(origin_rays(&first, {}), 5u);
    EXPECT_EQ(cache.size(), 4u);
    ASSERT_GT(first[4 * 9 + 1], 0.f);  // the centre is lit
    EXPECT_EQ(origin_rays(&again, {}), 1u);
    EXPECT_EQ(first, again);
    const std::vector<uint8_t> lit = {2};
    EXPECT_EQ(origin_rays(&known_e, lit), 5u);
}

// A split node's children's new probes may take the states the node's probes agreed on
// (Evaluate's `inherited`, from ProbeAgreement): the lit patch's four probes agree on every
// light target, so the same points with a new cache and that agreement trace no
// classification ray and get the same E; told the light is hidden instead, they take it
// as hidden. A key not in the cache gives no agreement.
TEST(DirectLight, NewProbesTakeInheritedStatesWithoutRays) {
    FoldScene f;
    DirectLight direct(f.scene, f.scene.solver, f.vis, 1e-3f, 100, 0.05f);
    std::vector<ReceiverPoint> pts;
    std::vector<ProbeKey> keys;
    ProbePatch(0.f, &pts, &keys);
    auto classify_rays = [&](ProbeCache* cache, std::span<const uint8_t> inherited,
                             std::vector<float>* e) {
        const uint64_t before = RaysByKind()[size_t(RayKind::kClassify)];
        direct.Evaluate(pts, *e, DirectLight::kLights, 4, cache, keys, {}, inherited);
        return RaysByKind()[size_t(RayKind::kClassify)] - before;
    };
    ProbeCache first_cache, second_cache, third_cache;
    std::vector<float> first(pts.size() * 9), second(pts.size() * 9), hidden(pts.size() * 9);
    EXPECT_EQ(classify_rays(&first_cache, {}, &first), 4u * 5u);  // the probes; the centre agrees
    ASSERT_GT(first[1], 0.f);
    const std::vector<uint8_t> agree = direct.ProbeAgreement(first_cache, keys);
    ASSERT_FALSE(agree.empty());
    EXPECT_TRUE(std::all_of(agree.begin(), agree.end(), [](uint8_t s) { return s == 2; }));
    EXPECT_EQ(classify_rays(&second_cache, agree, &second), 0u);
    EXPECT_EQ(first, second);
    const std::vector<uint8_t> all_hidden(agree.size(), 3);
    EXPECT_EQ(classify_rays(&third_cache, all_hidden, &hidden), 0u);
    EXPECT_EQ(hidden[1], 0.f);
    std::vector<ProbeKey> missing = keys;
    missing[3].u += 1;
    EXPECT_TRUE(direct.ProbeAgreement(first_cache, missing).empty());
}

// A chart's outline across a convex bend: face A (y = tA z, z < 0) is the chart's real
// edge, face B (y = -tB z, z > 0) the neighbour's. A virtual point of A just past the
// outline has its visibility point on the shared edge (here a hair on B's side, so the
// ray down from it meets B), its position and normal extrapolated along A. A small light
// at `elevation` degrees toward -z (toward: -1) or +z (+1), far away.
struct BendScene {
    Scene scene;
    VisibilityScene vis;
    PolygonLight light;
    BendScene(double ta, double tb, double elevation, double toward) {
        light = FarSquareLight(elevation, toward);
        scene.lights.push_back(light);
        const float fa = float(ta), fb = float(tb);
        std::vector<float> geo = {-1, -fa, -1, 1, -fa, -1, 1, 0, 0, -1, 0, 0,  // A
                                  1, -fb, 1, -1, -fb, 1};                      // B
        std::vector<uint32_t> tris = {0, 2, 1, 0, 3, 2, 3, 4, 2, 3, 5, 4};
        vis.AddTriangles(geo, tris, "bend");
        vis.Commit();
    }
    // The key light at A's virtual point, or at a real point at the same place.
    double LightAt(bool inside, bool outline) {
        scene.solver.outline_face_inside = inside;
        DirectLight direct(scene, scene.solver, vis, 1e-3f, 100, 0.05f);
        const Vec3f n(0, 1, 0);
        ReceiverPoint rp{{0, 0, 0.01f}, n, {0, 0, 2e-4f}, n};
        rp.outline = outline;
        std::vector<float> e(9);
        direct.Evaluate(std::span<const ReceiverPoint>(&rp, 1), e, DirectLight::kLights);
        return e[1];
    }
    double Lit() const {
        return IrradianceClipped(light.vertices, 100.0, Vec3d(0, 0, 0.01), Vec3d(0, 1, 0));
    }
};

// The neighbour's plane must not cut light the chart's own edge sees: A flat, B falling
// 30 degrees, the light 10 degrees up over A (below B's plane). With outline_face_inside
// the virtual point takes A's face and the light; a real point there keeps B's face.
TEST(DirectLight, OutlinePointTakesItsOwnEdgesFace) {
    BendScene s(0, std::tan(30 * std::numbers::pi / 180), 10, -1);
    const double lit = s.Lit();
    ASSERT_GT(lit, 0);
    EXPECT_NEAR(s.LightAt(false, true), 0, 1e-9);  // main's rule: B's plane cuts it
    EXPECT_NEAR(s.LightAt(true, true), lit, 1e-3 * lit);
    EXPECT_NEAR(s.LightAt(true, false), 0, 1e-9);  // not an outline point: as before
}

// ... and light the real edge's face does not see stays cut (a key grazing the edge,
// turbineblade): A rises 10 degrees toward the outline, its smooth normal straight up, the
// light 5 degrees up toward +z, above the normal's horizon and B's plane, below A's.
TEST(DirectLight, OutlinePointKeepsItsOwnEdgesCut) {
    const double d = std::numbers::pi / 180;
    BendScene s(std::tan(10 * d), std::tan(30 * d), 5, 1);
    const double lit = s.Lit();
    ASSERT_GT(lit, 0);
    EXPECT_NEAR(s.LightAt(false, true), lit, 1e-3 * lit);  // main's rule: B's plane, lit
    EXPECT_NEAR(s.LightAt(true, true), 0, 1e-9);           // A's own face cuts it
}


// EvaluateLight, AddLights, OnSurface, AddSky and the penumbra keep their buffers per thread
// (bench/RESULTS.md, issue 13 session 22): the same points give the same bits on a fresh
// thread as after other, larger evaluations on this one, with and without probes.
TEST(DirectLight, PerThreadBuffersDoNotCarryOver) {
    OccluderScene s(256);
    s.scene.sky.type = Sky::Type::Uniform;
    s.scene.sky.radiance = {0.3, 0.2, 0.1};
    s.scene.sky.up = {0, 1, 0};
    DirectLight direct(s.scene, s.scene.solver, s.vis, 1e-4f, 10);
    // Points across the penumbra, horizons tilted so that some cut the light.
    auto row = [](double from, double to, double step, float tilt) {
        std::vector<ReceiverPoint> pts;
        for (double x = from; x <= to; x += step) {
            const Vec3f p(float(x), 0, 0.1f);
            pts.push_back({p, {0, 1, 0}, p, Normalize(Vec3f(tilt * float(x), 1, 0))});
        }
        return pts;
    };
    const std::vector<ReceiverPoint> pts = row(0, 1.2, 0.1, 1.5f);
    for (size_t probes : {size_t(0), size_t(4)}) {
        std::vector<float> fresh(pts.size() * 9), again(pts.size() * 9);
        std::thread([&] { direct.Evaluate(pts, fresh, DirectLight::kAll, probes); }).join();
        const std::vector<ReceiverPoint> other = row(-1, 2.5, 0.03, -0.7f);
        std::vector<float> e_other(other.size() * 9);
        direct.Evaluate(other, e_other, DirectLight::kAll, probes);
        direct.Evaluate(pts, again, DirectLight::kAll, probes);
        EXPECT_EQ(fresh, again) << "probes " << probes;
        EXPECT_GT(*std::max_element(again.begin(), again.end()), 0.f);
    }
}


// The per-thread buffers are reused by calls one after the other, and a call nested on the
// same thread (a solver task run inside Embree's build of a paged piece) gets its own.
TEST(ThreadScratch, NestedUseGetsItsOwnBuffers) {
    struct Buffers {
        std::vector<int> v;
    };
    const Buffers* first = nullptr;
    {
        ThreadScratch<Buffers> outer;
        first = &*outer;
        outer->v.assign(3, 7);
        {
            ThreadScratch<Buffers> nested;
            EXPECT_NE(&*nested, first);
            EXPECT_TRUE(nested->v.empty());
            nested->v.assign(5, 1);
        }
        EXPECT_EQ(outer->v, std::vector<int>(3, 7));
    }
    ThreadScratch<Buffers> again;
    EXPECT_EQ(&*again, first);
}

}  // namespace
}  // namespace mebake::solve
