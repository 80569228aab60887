#include "solve/visibility.h"

#include "core/error.h"
#include "core/parallel.h"
#include "core/vec.h"
#include "solve/rays.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>
#include <xmmintrin.h>

namespace mebake::solve {
namespace {

constexpr TraceMethod kMethods[] = {TraceMethod::kStream, TraceMethod::kPacket16,
                                    TraceMethod::kPacket8, TraceMethod::kSingle};

Segment Seg(Vec3f a, Vec3f b, float tnear = 0, float tfar = 1) {
    return {a.x, a.y, a.z, tnear, b.x - a.x, b.y - a.y, b.z - a.z, tfar};
}

// One triangle in the plane z = 1 covering the square around (0,0).
void AddBlocker(VisibilityScene* scene) {
    const std::vector<float> p = {-1, -1, 1, 2, -1, 1, -1, 2, 1};
    const std::vector<uint32_t> t = {0, 1, 2};
    EXPECT_EQ(scene->AddTriangles(p, t), 0u);
}

TEST(Visibility, TriangleBetweenTwoPointsOccludes) {
    for (TraceMethod m : kMethods) {
        VisibilityOptions opt;
        opt.method = m;
        VisibilityScene scene(opt);
        AddBlocker(&scene);
        scene.Commit();
        EXPECT_EQ(scene.triangle_count(), 1u);
        const Vec3f below{0, 0, 0}, above{0, 0, 2};
        std::vector<Segment> segs = {
            Seg(below, above),               // crosses the triangle
            Seg(below, {0, 0, 0.9f}),        // stops short
            Seg(below, above, 0.6f, 1.0f),   // starts after the triangle (t = 0.5)
            Seg(below, above, 0.0f, 0.49f),  // tfar before it
            Seg(below, above, 0.0f, 0.51f),  // tfar just past it
            Seg({5, 5, 0}, {5, 5, 2}),       // misses beside it
            Seg(below, above, 0.7f, 0.2f),   // tnear > tfar: empty
            {0, 0, 0, 0, 0, 0, 1, std::numeric_limits<float>::infinity()},  // infinite ray
            Seg(above, below),  // from the back side too
        };
        std::vector<uint8_t> occ(segs.size(), 7);
        scene.Occluded(segs, occ);
        const std::vector<uint8_t> expect = {1, 0, 0, 0, 1, 0, 0, 1, 1};
        EXPECT_EQ(occ, expect) << "method " << int(m);

        std::vector<Hit> hits(segs.size());
        scene.Intersect(segs, hits);
        EXPECT_NEAR(hits[0].t, 0.5f, 1e-6f);
        EXPECT_EQ(hits[0].geom_id, 0u);
        EXPECT_EQ(hits[0].prim_id, 0u);
        EXPECT_NEAR(hits[0].ng_z / std::abs(hits[0].ng_z), 1.0f, 0.0f);
        EXPECT_EQ(hits[1].geom_id, kNoHit);
        EXPECT_EQ(hits[5].prim_id, kNoHit);
        EXPECT_NEAR(hits[7].t, 1.0f, 1e-6f);
    }
}

TEST(Visibility, QueriesRestoreTheCallersFloatMode) {
    VisibilityScene scene;
    AddBlocker(&scene);
    scene.Commit();
    const unsigned before = _mm_getcsr();
    std::vector<Segment> segs = {Seg({0, 0, 0}, {0, 0, 2})};
    std::vector<uint8_t> occ(1);
    scene.Occluded(segs, occ);
    std::vector<Hit> hits(1);
    scene.Intersect(segs, hits);
    EXPECT_EQ(_mm_getcsr(), before);
    EXPECT_EQ(occ[0], 1);
}

TEST(Visibility, MalformedInputIsAnError) {
    VisibilityScene scene;
    const std::vector<float> p = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    EXPECT_THROW(scene.AddTriangles(p, std::vector<uint32_t>{0, 1, 3}), Error);
    EXPECT_THROW(scene.AddTriangles(p, std::vector<uint32_t>{0, 1}), Error);
    EXPECT_THROW(scene.AddTriangles(std::vector<float>{0, 0}, std::vector<uint32_t>{}), Error);
    // Non-finite vertices: the triangle is ignored, nothing crashes.
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::vector<float> bad = {0, 0, 1, nan, 0, 1, 0, 1, 1};
    EXPECT_EQ(scene.AddTriangles(bad, std::vector<uint32_t>{0, 1, 2}), 0u);
    EXPECT_EQ(scene.AddTriangles({}, {}), 1u);  // empty meshes keep their id
    EXPECT_EQ(scene.AddTriangles(p, std::vector<uint32_t>{0, 1, 2}), 2u);
    scene.Commit();
    std::vector<Segment> segs = {Seg({0.2f, 0.2f, -1}, {0.2f, 0.2f, 1}),
                                 Seg({0.1f, 0.1f, 0.5f}, {0.1f, 0.1f, 1.5f})};
    std::vector<uint8_t> occ(2);
    scene.Occluded(segs, occ);
    EXPECT_EQ(occ[0], 1);
    std::vector<Hit> hits(2);
    scene.Intersect(segs, hits);
    EXPECT_EQ(hits[0].geom_id, 2u);
}

// Brute-force Moller-Trumbore in double. Reports whether the answer could depend on
// rounding (hit point near an edge, near the segment's ends, or a grazing ray).
struct BruteHit {
    bool hit = false;
    bool ambiguous = false;
    double t = 0;
};

BruteHit RayTriangle(const Segment& s, const float* a, const float* b, const float* c) {
    const double o[3] = {s.ox, s.oy, s.oz}, d[3] = {s.dx, s.dy, s.dz};
    double e1[3], e2[3], p[3], q[3], tv[3];
    for (int i = 0; i < 3; ++i) {
        e1[i] = double(b[i]) - a[i];
        e2[i] = double(c[i]) - a[i];
        tv[i] = o[i] - a[i];
    }
    auto cross = [](const double* x, const double* y, double* r) {
        r[0] = x[1] * y[2] - x[2] * y[1];
        r[1] = x[2] * y[0] - x[0] * y[2];
        r[2] = x[0] * y[1] - x[1] * y[0];
    };
    auto dot = [](const double* x, const double* y) {
        return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    };
    cross(d, e2, p);
    const double det = dot(e1, p);
    BruteHit h;
    double n[3];
    cross(e1, e2, n);
    const double scale = std::sqrt(dot(n, n) * dot(d, d));
    if (std::abs(det) < 1e-6 * scale) {
        h.ambiguous = true;  // grazing
        return h;
    }
    const double u = dot(tv, p) / det;
    cross(tv, e1, q);
    const double v = dot(d, q) / det;
    const double t = dot(e2, q) / det;
    const double eps = 1e-4;
    // margin >= 0 inside the triangle; |margin| small means the crossing is near its boundary.
    const double margin = std::min({u, v, 1 - u - v});
    const bool inside = margin >= 0;
    const bool near_edge = std::abs(margin) < eps;
    const bool in_range = t >= s.tnear && t <= s.tfar;
    const bool near_end = std::abs(t - s.tnear) < eps || std::abs(t - s.tfar) < eps;
    h.hit = inside && in_range;
    h.t = t;
    if ((near_edge && (in_range || near_end)) || (near_end && (inside || near_edge)))
        h.ambiguous = true;
    return h;
}

struct Soup {
    std::vector<float> p;
    std::vector<uint32_t> t;
};

Soup RandomSoup(int triangles, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0, 1), e(-0.03f, 0.03f);
    Soup s;
    for (int i = 0; i < triangles; ++i) {
        const float cx = u(rng), cy = u(rng), cz = u(rng);
        for (int k = 0; k < 3; ++k) {
            s.p.push_back(cx + e(rng));
            s.p.push_back(cy + e(rng));
            s.p.push_back(cz + e(rng));
            s.t.push_back(uint32_t(3 * i + k));
        }
    }
    return s;
}

std::vector<Segment> RandomSegments(int n, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-0.1f, 1.1f), f(0, 1);
    std::vector<Segment> segs;
    for (int i = 0; i < n; ++i) {
        Segment s = Seg({u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)});
        if (i % 4 == 1)
            s.tnear = 0.3f * f(rng);
        if (i % 4 == 2)
            s.tfar = 0.5f + 0.5f * f(rng);
        segs.push_back(s);
    }
    return segs;
}

TEST(Visibility, RandomSoupAgreesWithBruteForce) {
    const Soup soup = RandomSoup(2000, 21);
    const std::vector<Segment> segs = RandomSegments(10000, 22);
    const size_t nt = soup.t.size() / 3;
    std::vector<BruteHit> closest(segs.size());
    std::vector<uint32_t> closest_prim(segs.size(), kNoHit);
    std::vector<uint8_t> brute(segs.size()), ambiguous(segs.size());
    for (size_t i = 0; i < segs.size(); ++i) {
        double best = 1e30, second = 1e30;
        for (size_t k = 0; k < nt; ++k) {
            const BruteHit h =
                RayTriangle(segs[i], &soup.p[3 * soup.t[3 * k]], &soup.p[3 * soup.t[3 * k + 1]],
                            &soup.p[3 * soup.t[3 * k + 2]]);
            if (h.ambiguous)
                ambiguous[i] = 1;
            if (h.hit) {
                brute[i] = 1;
                if (h.t < best) {
                    second = best;
                    best = h.t;
                    closest_prim[i] = uint32_t(k);
                } else {
                    second = std::min(second, h.t);
                }
            }
        }
        closest[i].t = best;
        if (second < 1e30 && second - best < 1e-4)
            ambiguous[i] = 1;  // near tie
    }
    int compared = 0, occluded = 0;
    for (size_t i = 0; i < segs.size(); ++i) {
        compared += !ambiguous[i];
        occluded += !ambiguous[i] && brute[i];
    }
    std::printf("%d of %zu segments unambiguous, %d of them occluded\n", compared, segs.size(),
                occluded);
    EXPECT_GT(compared, 9000);
    EXPECT_GT(occluded, 1000);
    EXPECT_LT(occluded, compared - 1000);

    std::vector<uint8_t> first;
    for (TraceMethod m : kMethods) {
        for (bool robust : {true, false}) {
            VisibilityOptions opt;
            opt.method = m;
            opt.robust = robust;
            VisibilityScene scene(opt);
            scene.AddTriangles(soup.p, soup.t);
            scene.Commit();
            std::vector<uint8_t> occ(segs.size());
            scene.Occluded(segs, occ);
            std::vector<Hit> hits(segs.size());
            scene.Intersect(segs, hits);
            int mismatches = 0;
            for (size_t i = 0; i < segs.size(); ++i) {
                if (ambiguous[i])
                    continue;
                if (occ[i] != brute[i])
                    ++mismatches;
                EXPECT_EQ(hits[i].prim_id, closest_prim[i]) << i;
                if (closest_prim[i] != kNoHit) {
                    EXPECT_NEAR(hits[i].t, closest[i].t, 1e-5);
                }
            }
            EXPECT_EQ(mismatches, 0) << "method " << int(m) << " robust " << robust;
            // Every method gives the same bits, ambiguous segments included (robust mode).
            if (robust) {
                if (first.empty()) {
                    first = occ;
                } else {
                    EXPECT_EQ(occ, first) << "method " << int(m);
                }
            }
        }
    }
}

TEST(Visibility, SharedBuffersGiveTheSameAnswers) {
    Soup soup = RandomSoup(3000, 71);
    const size_t nv = soup.p.size() / 3;
    const std::vector<Segment> segs = RandomSegments(5000, 72);
    VisibilityScene copied;
    copied.AddTriangles(soup.p, soup.t);
    copied.Commit();
    std::vector<float> padded = soup.p;
    EXPECT_THROW(VisibilityScene().AddTrianglesShared(padded, nv, soup.t), Error);  // no spare
    padded.push_back(0.0f);
    const int64_t before = EmbreeMemoryBytes();
    VisibilityScene shared;
    EXPECT_EQ(shared.AddTrianglesShared(padded, nv, soup.t), 0u);
    shared.Commit();
    // The BVH is counted, the shared arrays are not.
    EXPECT_GT(EmbreeMemoryBytes(), before);
    std::vector<uint8_t> a(segs.size()), b(segs.size());
    copied.Occluded(segs, a);
    shared.Occluded(segs, b);
    EXPECT_EQ(a, b);
    std::vector<uint32_t> bad = {0, 1, uint32_t(nv)};
    EXPECT_THROW(VisibilityScene().AddTrianglesShared(padded, nv, bad), Error);
}

TEST(Visibility, ConcurrentQueriesMatchSerial) {
    const Soup soup = RandomSoup(20000, 31);
    const std::vector<Segment> segs = RandomSegments(50000, 32);
    VisibilityScene scene;
    scene.AddTriangles(soup.p, soup.t);
    scene.Commit();
    std::vector<uint8_t> serial(segs.size()), parallel(segs.size()), tasks(segs.size());
    scene.Occluded(segs, serial);
    scene.OccludedParallel(segs, parallel);
    EXPECT_EQ(serial, parallel);
    TaskGroup group;
    const size_t half = segs.size() / 2;
    group.Run([&] {
        scene.Occluded(std::span(segs).subspan(0, half), std::span(tasks).subspan(0, half));
    });
    group.Run(
        [&] { scene.Occluded(std::span(segs).subspan(half), std::span(tasks).subspan(half)); });
    group.Wait();
    EXPECT_EQ(serial, tasks);
}

TEST(Visibility, MemoryIsCountedAndCanBeCapped) {
    const int64_t before = EmbreeMemoryBytes();
    const Soup soup = RandomSoup(100000, 41);
    {
        VisibilityScene scene;
        scene.AddTriangles(soup.p, soup.t);
        scene.Commit();
        const int64_t during = EmbreeMemoryBytes();
        // At least the vertex and index copies, and a BVH.
        EXPECT_GT(during - before, int64_t(soup.p.size() * 4 + soup.t.size() * 4));
        EXPECT_GE(EmbreePeakMemoryBytes(), during);
        std::printf("Embree holds %.1f MB for 100K triangles (compact, robust)\n",
                    (during - before) / 1e6);
    }
    EXPECT_LE(EmbreeMemoryBytes() - before, 1 << 20);  // released again (allocator slack)

    SetEmbreeMemoryLimit(EmbreeMemoryBytes() + 200000);
    bool threw = false;
    try {
        VisibilityScene scene;
        scene.AddTriangles(soup.p, soup.t);
        scene.Commit();
    } catch (const Error& e) {
        threw = true;
        EXPECT_NE(std::string(e.what()).find("Embree"), std::string::npos) << e.what();
        std::printf("over the limit: %s\n", e.what());
    }
    SetEmbreeMemoryLimit(0);
    EXPECT_TRUE(threw);
    // Works again without the limit.
    VisibilityScene scene;
    scene.AddTriangles(soup.p, soup.t);
    scene.Commit();
    std::vector<Segment> segs = RandomSegments(100, 42);
    std::vector<uint8_t> occ(segs.size());
    scene.Occluded(segs, occ);
}

struct HeightField {
    std::vector<float> p;
    std::vector<uint32_t> t;
    static float Height(float x, float y) {
        return 0.05f * std::sin(40 * x) * std::cos(37 * y) + 0.1f * std::sin(7 * x + 3 * y);
    }
    explicit HeightField(int n) {
        for (int j = 0; j <= n; ++j) {
            for (int i = 0; i <= n; ++i) {
                const float x = float(i) / n, y = float(j) / n;
                p.insert(p.end(), {x, y, Height(x, y)});
            }
        }
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n + 1),
                               d = c + 1;
                t.insert(t.end(), {a, b, d, a, d, c});
            }
        }
    }
};

TEST(Visibility, CoherentBundlesDoNotHangAndAgree) {
    // Bundles of 256 segments between two 0.02-wide patches: with the coherent context flag
    // Embree's rtcOccluded16 never returned on this input, so the wrapper gives that flag to
    // the stream API only. Every method and flag must agree.
    const HeightField field(300);
    std::mt19937 rng(61);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<Segment> segs(4096);
    float px = 0, py = 0, qx = 0, qy = 0;
    for (size_t i = 0; i < segs.size(); ++i) {
        if (i % 256 == 0) {
            px = 0.98f * u(rng), py = 0.98f * u(rng), qx = 0.98f * u(rng), qy = 0.98f * u(rng);
        }
        const float x0 = px + 0.02f * u(rng), y0 = py + 0.02f * u(rng);
        const float x1 = qx + 0.02f * u(rng), y1 = qy + 0.02f * u(rng);
        segs[i] = Seg({x0, y0, HeightField::Height(x0, y0) + 0.01f},
                      {x1, y1, HeightField::Height(x1, y1) + 0.01f});
    }
    std::vector<uint8_t> first;
    for (TraceMethod m : kMethods) {
        for (bool coherent : {false, true}) {
            VisibilityOptions opt;
            opt.method = m;
            opt.coherent = coherent;
            VisibilityScene scene(opt);
            scene.AddTriangles(field.p, field.t);
            scene.Commit();
            std::vector<uint8_t> occ(segs.size());
            scene.Occluded(segs, occ);
            if (first.empty())
                first = occ;
            EXPECT_EQ(occ, first) << "method " << int(m) << " coherent " << coherent;
        }
    }
}

TEST(Visibility, RayRateOnABumpyHeightField) {
    // A 300 x 300 x 2 = 180K-triangle height field; segments between points just above it.
    // (The full-size measurement, ~1M triangles, is bench/embree_rate_bench.cpp.)
    const HeightField field(300);
    const auto& p = field.p;
    const auto& t = field.t;
    auto height = HeightField::Height;
    std::mt19937 rng(51);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<Segment> segs(200000);
    for (Segment& s : segs) {
        const float x0 = u(rng), y0 = u(rng), x1 = u(rng), y1 = u(rng);
        s = Seg({x0, y0, height(x0, y0) + 0.01f}, {x1, y1, height(x1, y1) + 0.01f});
    }
    for (TraceMethod m : kMethods) {
        VisibilityOptions opt;
        opt.method = m;
        VisibilityScene scene(opt);
        scene.AddTriangles(p, t);
        scene.Commit();
        std::vector<uint8_t> occ(segs.size());
        const auto t0 = std::chrono::steady_clock::now();
        scene.Occluded(segs, occ);
        const double sec =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        int blocked = 0;
        for (uint8_t o : occ)
            blocked += o;
        std::printf("method %d: %.2f M occlusion rays/s (1 thread), %.0f%% occluded\n", int(m),
                    segs.size() / sec * 1e-6, 100.0 * blocked / segs.size());
        EXPECT_GT(blocked, 0);
        EXPECT_LT(blocked, int(segs.size()));
    }
}

// A link's ray leaves out where it is inside both a sample's sphere and the slab of its
// relief, at either end (what it meets there may be that sample's own surface), keeping
// [0.25, 0.5]; a surface above the slab (a box beside a flat sample) still blocks.
TEST(Visibility, SegmentBetweenSamplesIgnoresOnlyTheirOwnSlabs) {
    VisibilityScene scene;
    AddBlocker(&scene);  // z = 1
    scene.Commit();
    const Vec3f o{0, 0, 0}, down{0, 0, -1}, up{0, 0, 1};
    const SampleBound none{o, up, 0.f, 0.f};
    // Emitter samples at z = h facing o, the ray's end 0.01 above them.
    auto end = [](float h) { return Vec3f{0, 0, h - 0.01f}; };
    auto emitter = [&](float h, float radius, float relief) {
        return SampleBound{{0, 0, h}, down, radius, relief};
    };
    SegmentBatch batch;
    batch.AddSegmentBetween(o, end(1.2f), none, emitter(1.2f, 0.3f, 0.25f));  // in both: free
    batch.AddSegmentBetween(o, end(1.2f), none, emitter(1.2f, 0.3f, 0.1f));   // above the slab
    batch.AddSegmentBetween(o, end(1.2f), none, emitter(1.2f, 0.1f, 0.25f));  // outside the sphere
    batch.AddSegmentBetween(o, end(1.2f), none, emitter(1.2f, 0.3f, 0.f));    // flat: AddSegment's
    batch.AddSegmentBetween(o, end(1.8f), none, emitter(1.8f, 5.f, 5.f));     // half kept: 0.895
    batch.AddSegmentBetween(o, end(2.1f), none, emitter(2.1f, 5.f, 5.f));     // half kept: 1.045
    batch.AddSegmentBetween(o, o, none, emitter(1.2f, 1.f, 1.f));             // empty
    // Receiver samples at z = h facing up, the ray's start 0.01 above them, towards z = 2.
    const Vec3f top{0, 0, 2};
    auto start = [](float h) { return Vec3f{0, 0, h + 0.01f}; };
    auto receiver = [&](float h, float radius, float relief) {
        return SampleBound{{0, 0, h}, up, radius, relief};
    };
    batch.AddSegmentBetween(start(0.8f), top, receiver(0.8f, 0.3f, 0.25f), none);  // free
    batch.AddSegmentBetween(start(0.8f), top, receiver(0.8f, 0.3f, 0.1f), none);   // blocks
    batch.AddSegmentBetween(start(0.8f), top, receiver(0.8f, 0.1f, 0.25f), none);  // blocks
    batch.AddSegmentBetween(start(0.5f), top, receiver(0.5f, 5.f, 5.f), none);     // from z 0.8825
    batch.AddSegmentBetween(start(0.8f), top, receiver(0.8f, 5.f, 5.f), none);     // from z 1.1075
    batch.Trace(scene);
    const std::vector<uint8_t> expect = {0, 1, 1, 1, 0, 1, 0, 0, 1, 1, 1, 0};
    EXPECT_EQ(batch.occluded, expect);
    EXPECT_FLOAT_EQ(batch.segments[0].tfar, (1.2f - 0.25f) / 1.19f);
    EXPECT_FLOAT_EQ(batch.segments[3].tfar, 0.999f);
    EXPECT_FLOAT_EQ(batch.segments[4].tfar, 0.5f);
    EXPECT_FLOAT_EQ(batch.segments[3].tnear, 0.f);
    EXPECT_FLOAT_EQ(batch.segments[7].tnear, (0.25f - 0.01f) / 1.19f);
    EXPECT_FLOAT_EQ(batch.segments[10].tnear, 0.25f);
}

}  // namespace
}  // namespace mebake::solve
