// The path-traced reference (reference/reference.h) against closed forms: Lambert's square light
// over a plane, a uniform sky over a plane, and the furnace (a closed emitting cube, where
// B = pi Le / (1 - rho) everywhere); its determinism across thread counts; and the probe
// (output/probe.h) on a hand-made solved bake.
#include "reference/reference.h"

#include "core/parallel.h"
#include "output/bake_view.h"
#include "output/probe.h"
#include "solve/polygon_light.h"
#include "solve/sky.h"
#include "support/bake_fixture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace mebake::reference {
namespace {

constexpr double kPi = std::numbers::pi;

solve::Scene OneMaterial(float albedo, Vec3f emission = {}) {
    solve::Scene s;
    solve::Material m;
    m.albedo = Vec3f(albedo, albedo, albedo);
    m.use_vertex_colors = false;
    m.emission = emission;
    s.per_input = {{m}};
    return s;
}

void AddQuad(ReferenceMesh& mesh, Vec3f a, Vec3f b, Vec3f c, Vec3f d) {  // a b c d CCW = front
    const uint32_t base = uint32_t(mesh.position.size());
    const Vec3f n = Normalize(Cross(b - a, c - a));
    for (const Vec3f& p : {a, b, c, d}) {
        mesh.position.push_back(p);
        mesh.normal.push_back(n);
        mesh.uv.push_back(Vec2f(0.5f, 0.5f));
    }
    for (std::array<uint32_t, 3> f : {std::array<uint32_t, 3>{base, base + 1, base + 2},
                                      std::array<uint32_t, 3>{base, base + 2, base + 3}}) {
        mesh.local_triangle.push_back(uint32_t(mesh.triangles.size()));
        mesh.triangles.push_back(f);
        mesh.material.push_back(0);
        mesh.chart.push_back(0);
    }
}

ReferenceMesh Plane(float half) {
    ReferenceMesh m;
    AddQuad(m, {-half, -half, 0}, {half, -half, 0}, {half, half, 0}, {-half, half, 0});
    return m;
}

ReferenceOptions Fast(double target) {
    ReferenceOptions o;
    o.seed = 7;
    o.min_samples = 1024;
    o.max_samples = 1 << 15;
    o.target_relative_error = target;
    o.floor_fraction = 0;
    return o;
}

// Each test makes tens of comparisons with the estimator's own standard error: at 3 se a
// correct estimator fails one run in a few dozen (seen with clang's floating point); at 4 se
// one in ~10^4, while a bias of a few percent still fails.
constexpr double kSe = 4;

void ExpectWithinSe(double value, double se, double expected, const char* what, int i) {
    EXPECT_GT(se, 0) << what << " point " << i;
    EXPECT_NEAR(value, expected, kSe * se) << what << " point " << i << " (se " << se << ")";
}

TEST(ReferenceTest, SquareLightOverPlaneMatchesLambert) {
    const ReferenceMesh mesh = Plane(50);  // big enough to sample points under the light
    solve::Scene scene = OneMaterial(0.5f);
    solve::PolygonLight light;
    // A unit square at height 1, facing down (counter-clockwise seen from below).
    light.vertices = {{-0.5, -0.5, 1}, {-0.5, 0.5, 1}, {0.5, 0.5, 1}, {0.5, -0.5, 1}};
    light.radiance = Vec3d(1, 2, 3);
    scene.lights.push_back(light);
    const ReferenceTracer tracer(mesh, scene);
    // Points under and beside the light (chosen by hand rather than at random).
    auto points = ChooseReferencePoints(mesh, scene, 4, 3);
    const Vec3d where[4] = {{0, 0, 0}, {0.3, 0.1, 0}, {1.2, -0.4, 0}, {-2, 1.5, 0}};
    for (int i = 0; i < 4; ++i) {
        auto& p = points[size_t(i)];
        p.position = where[i];
        p.normal = p.geometric_normal = Vec3d(0, 0, 1);
    }
    const ReferenceStats st = tracer.Estimate(points, Fast(0.003));
    EXPECT_GT(st.rays, 0u);
    for (int i = 0; i < 4; ++i) {
        const auto& p = points[size_t(i)];
        const double irr = solve::IrradianceClipped(light.vertices, 1.0, where[i], Vec3d(0, 0, 1));
        const Vec3d e = solve::VectorIrradiance(light.vertices, 1.0, where[i]);
        for (int c = 0; c < 3; ++c) {
            ExpectWithinSe(p.b[c], p.b_se[c], 0.5 * light.radiance[c] * irr, "B", i);
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(p.e[size_t(c)][k], light.radiance[c] * e[k],
                            kSe * p.e_se[size_t(c)][k] + 1e-12)
                    << "E point " << i << " colour " << c << " axis " << k;
        }
    }
}

TEST(ReferenceTest, UniformSkyOverPlane) {
    const ReferenceMesh mesh = Plane(1);
    solve::Scene scene = OneMaterial(0.6f);
    scene.sky.type = solve::Sky::Type::Uniform;
    scene.sky.radiance = Vec3d(0.5, 1, 2);
    scene.sky.up = Vec3d(0, 0, 1);
    const ReferenceTracer tracer(mesh, scene);
    auto points = ChooseReferencePoints(mesh, scene, 3, 11);
    tracer.Estimate(points, Fast(0.003));
    for (int i = 0; i < 3; ++i)
        for (int c = 0; c < 3; ++c) {
            const auto& p = points[size_t(i)];
            ExpectWithinSe(p.b[c], p.b_se[c], 0.6 * kPi * scene.sky.radiance[c], "B", i);
            EXPECT_NEAR(p.e[size_t(c)].z, kPi * scene.sky.radiance[c], kSe * p.e_se[size_t(c)].z);
        }
}

// Inward-facing unit cube; every face emits Le and reflects rho.
ReferenceMesh InwardCube() {
    ReferenceMesh m;
    const Vec3f v[8] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                        {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    // Each face listed counter-clockwise seen from outside, added reversed (front = inside).
    const int faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                             {3, 7, 6, 2}, {0, 4, 7, 3}, {1, 2, 6, 5}};
    for (const auto& f : faces)
        AddQuad(m, v[f[3]], v[f[2]], v[f[1]], v[f[0]]);
    return m;
}

TEST(ReferenceTest, FurnaceMatchesGeometricSeries) {
    const ReferenceMesh mesh = InwardCube();
    for (int k = 0; k < 6; ++k) {  // the normals really point inwards
        const auto& f = mesh.triangles[size_t(2 * k)];
        const Vec3f centre =
            (mesh.position[f[0]] + mesh.position[f[1]] + mesh.position[f[2]]) / 3.f;
        EXPECT_GT(Dot(mesh.normal[f[0]], Vec3f(0.5f, 0.5f, 0.5f) - centre), 0);
    }
    const float rho = 0.7f;
    const Vec3f le(1, 0.5f, 0.25f);
    const solve::Scene scene = OneMaterial(rho, le);
    const ReferenceTracer tracer(mesh, scene);
    auto points = ChooseReferencePoints(mesh, scene, 5, 5);
    tracer.Estimate(points, Fast(0.003));
    for (int i = 0; i < 5; ++i) {
        const auto& p = points[size_t(i)];
        for (int c = 0; c < 3; ++c) {
            const double b = kPi * le[c] / (1 - rho);
            ExpectWithinSe(p.b[c], p.b_se[c], b, "B", i);
            // E = integral of L w over the hemisphere = pi L n with L = B / pi.
            const Vec3d e = p.geometric_normal * b;
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(p.e[size_t(c)][k], e[k], kSe * p.e_se[size_t(c)][k] + 1e-9);
        }
    }
}

TEST(ReferenceTest, SameResultForAnyThreadCount) {
    const ReferenceMesh mesh = InwardCube();
    const solve::Scene scene = OneMaterial(0.5f, Vec3f(1, 1, 1));
    const ReferenceTracer tracer(mesh, scene);
    ReferenceOptions o = Fast(0.001);
    o.min_samples = 64;
    o.max_samples = 256;
    auto a = ChooseReferencePoints(mesh, scene, 16, 9);
    auto b = a;
    {
        ThreadLimit one(1);
        tracer.Estimate(a, o);
    }
    tracer.Estimate(b, o);
    for (size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].samples, b[i].samples);
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(a[i].b[c], b[i].b[c]);
            EXPECT_EQ(a[i].b_se[c], b[i].b_se[c]);
        }
    }
}

TEST(ReferenceTest, PointsAreAreaWeightedAndDeterministic) {
    ReferenceMesh mesh;
    AddQuad(mesh, {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});  // area 1
    AddQuad(mesh, {2, 0, 0}, {5, 0, 0}, {5, 1, 0}, {2, 1, 0});  // area 3
    const solve::Scene scene = OneMaterial(0.5f);
    const auto a = ChooseReferencePoints(mesh, scene, 4000, 1);
    const auto b = ChooseReferencePoints(mesh, scene, 4000, 1);
    int big = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].position, b[i].position);
        big += a[i].triangle >= 2;
        EXPECT_EQ(a[i].position.x >= 2, a[i].triangle >= 2);
    }
    EXPECT_NEAR(big / 4000.0, 0.75, 0.03);
    EXPECT_THROW(ChooseReferencePoints(mesh, scene, 0, 1), Error);
}

// On a hand-made solved bake (bake_fixture.h: two unit squares under a uniform sky, with a
// made-up field): the reference sees the sky's closed form, and the probe returns exactly
// the field the fixture wrote.
TEST(ReferenceTest, BakeDirectoryReferenceAndProbe) {
    const std::string dir = solve::testing::FreshDir("reference");
    solve::testing::TinyBakeOptions opt;
    opt.light[0].b = Vec3f(1, 1, 1);
    solve::testing::WriteTinyBake(dir, opt);
    // The fields as written: the charts disagree at x = 1 (stitching is output's stitch_test).
    const output::BakeView view =
        output::OpenBakeView(dir, output::FieldLoading::All, output::SeamStitching::Off);
    const ReferenceMesh mesh = LoadReferenceMesh(dir, view.manifest);
    ASSERT_EQ(mesh.triangles.size(), 4u);
    auto points = ChooseReferencePoints(mesh, view.scene, 6, 2);
    const ReferenceTracer tracer(mesh, view.scene);
    tracer.Estimate(points, Fast(0.005));
    std::vector<output::ProbeSite> sites;
    for (const auto& p : points) {
        for (int c = 0; c < 3; ++c) {
            const solve::SkyModel sky = solve::SkyModel::Uniform(view.scene.sky.radiance[c], view.scene.sky.up);
            ExpectWithinSe(p.b[c], p.b_se[c], 0.5 * solve::SkyIrradiance(sky, Vec3d(0, 0, 1)), "B", 0);
        }
        sites.push_back({p.chart, p.local_triangle, p.barycentric});
    }
    const auto values = output::ProbeSolution(view, sites);
    for (size_t i = 0; i < points.size(); ++i) {
        const Vec3f expected = solve::testing::ExpectedB(opt, int(points[i].chart), points[i].uv.x);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(values[i].b[c], expected[c], 1e-4f * expected[c]);
    }
    // A flat face: the shading normal is the face's, and the display rule applied to the
    // reference's own E is the reference's B (the same paths, n . E sample by sample).
    for (size_t i = 0; i < points.size(); ++i) {
        EXPECT_NEAR(Dot(values[i].normal, values[i].face_normal), 1, 1e-6);
        const Vec3d rule = output::DisplayRule(values[i], points[i].e.data());
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(rule[c], points[i].b[c], 1e-5 * points[i].b[c]);
    }
    sites.push_back({0, 99, Vec3f(1, 0, 0)});
    EXPECT_THROW(output::ProbeSolution(view, sites), Error);
    std::filesystem::remove_all(dir);
}

// The display rule on another E: pi Le + rho (n . E)+ per colour, clamped where E points
// below the shading normal's plane.
TEST(ReferenceTest, DisplayRuleOfAnotherIrradiance) {
    output::ProbeValue v;
    v.normal = Vec3f(0, 0, 1);
    v.albedo = Vec3f(0.5f, 0.5f, 0.5f);
    v.emission = Vec3f(0.1f, 0, 0);
    const Vec3d e[3] = {{0.3, 0, 2}, {5, 0, -1}, {0, 0, 4}};
    const Vec3d b = output::DisplayRule(v, e);
    EXPECT_NEAR(b[0], std::numbers::pi * 0.1 + 0.5 * 2, 1e-6);
    EXPECT_NEAR(b[1], 0, 1e-12);
    EXPECT_NEAR(b[2], 2, 1e-6);
}

TEST(ReferenceTest, CompareRadiosityMetrics) {
    const std::vector<Vec3d> ref = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
    const std::vector<Vec3d> se(4, Vec3d(0.01, 0, 0));
    std::vector<Vec3d> bake = ref;
    bake[3] = Vec3d(1.1, 1, 1);
    const output::ProbeError e = output::CompareRadiosity(ref, se, bake);
    const double level = std::sqrt(6.0 / 4);
    EXPECT_NEAR(e.relative_rms, std::sqrt(0.01 / 4) / level, 1e-12);
    EXPECT_NEAR(e.relative_max, 0.1 / level, 1e-12);
    EXPECT_NEAR(e.noise_rms, 0.01 / level, 1e-12);
    EXPECT_DOUBLE_EQ(e.median_relative, 0);
}

}  // namespace
}  // namespace mebake::reference
