// Paged visibility (solve/paged_visibility.h) gives a whole scene's answers, whatever the
// piece size, the cache and the threads.
#include "solve/paged_visibility.h"

#include "core/parallel.h"
#include "core/vec.h"
#include "solve/solve_job.h"
#include "solve/visibility.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

namespace mebake::solve {
namespace {

struct Geometry {
    std::vector<float> p;
    std::vector<uint32_t> t;
};

// A bumpy sphere (coherent, like a scan) centred at c.
Geometry Sphere(int n, Vec3f c, float radius) {
    Geometry g;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= 2 * n; ++i) {
            const double th = M_PI * j / n, ph = M_PI * i / n;
            const double r = radius * (1 + 0.1 * std::sin(9 * th) * std::cos(7 * ph));
            g.p.insert(g.p.end(), {float(c.x + r * std::sin(th) * std::cos(ph)),
                                   float(c.y + r * std::sin(th) * std::sin(ph)),
                                   float(c.z + r * std::cos(th))});
        }
    const uint32_t w = uint32_t(2 * n + 1);
    for (uint32_t j = 0; j < uint32_t(n); ++j)
        for (uint32_t i = 0; i < uint32_t(2 * n); ++i) {
            const uint32_t a = j * w + i;
            g.t.insert(g.t.end(), {a, a + 1, a + w + 1, a, a + w + 1, a + w});
        }
    return g;
}

// Random small triangles in the box [-2, 2]^3.
Geometry Soup(int n, unsigned seed) {
    Geometry g;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> f(-2, 2), e(-0.2f, 0.2f);
    for (int k = 0; k < n; ++k) {
        const Vec3f c(f(rng), f(rng), f(rng));
        for (int v = 0; v < 3; ++v)
            g.p.insert(g.p.end(), {c.x + e(rng), c.y + e(rng), c.z + e(rng)});
        g.t.insert(g.t.end(), {uint32_t(3 * k), uint32_t(3 * k + 1), uint32_t(3 * k + 2)});
    }
    return g;
}

// The geometries: two spheres, an empty one (ids must stay aligned), a soup.
std::vector<Geometry> Scene() {
    return {Sphere(40, Vec3f(-0.8f, 0, 0), 0.7f), Sphere(30, Vec3f(0.9f, 0.2f, 0.1f), 0.6f), {},
            Soup(1500, 3)};
}

void Fill(VisibilityScene* scene, const std::vector<Geometry>& geoms) {
    for (const Geometry& g : geoms)
        scene->AddTriangles(g.p, g.t);
    scene->Commit();
}

// The same hit's t, u, v and normal from the whole scene and from its pieces. Exact on an
// AVX-512 machine; on an AVX2-only one (Debian's Embree 3.13.5 runs other kernels there)
// the pieces' values differ in their last bits (seen: t 0.00095203053 vs 0.00095203146;
// barycentrics by up to 3e-6 on triangles of 1e-3 area, whose u = U / det magnifies it),
// while the triangle found is the same. Rounding, never another triangle.
bool Near(float a, float b, float scale) {
    return std::abs(a - b) <= 1e-6f * std::max(scale, 1.f);
}
bool SameHitValues(const Hit& a, const Hit& b) {
    const float ng = std::max({std::abs(a.ng_x), std::abs(a.ng_y), std::abs(a.ng_z)});
    return Near(a.t, b.t, std::abs(a.t)) && Near(a.u, b.u, 20) && Near(a.v, b.v, 20) &&
           Near(a.ng_x, b.ng_x, ng) && Near(a.ng_y, b.ng_y, ng) && Near(a.ng_z, b.ng_z, ng);
}

std::vector<Segment> Segments(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> f(-2.5f, 2.5f), u(0, 1);
    std::vector<Segment> segs;
    for (int i = 0; i < n; ++i) {
        Segment s{f(rng), f(rng), f(rng), 0, f(rng), f(rng), f(rng), 1};
        if (i % 5 == 0)
            s.tfar = INFINITY;  // rays
        if (i % 13 == 0)
            s.tnear = u(rng);
        if (i % 17 == 0)
            s.dx = s.dy = 0;  // axis-parallel
        segs.push_back(s);
    }
    return segs;
}

TEST(PagedVisibility, SameAnswersAsOneSceneForAnyPiecesAndCache) {
    const auto geoms = Scene();
    const std::vector<Segment> segs = Segments(20000, 9);
    VisibilityScene whole;
    Fill(&whole, geoms);
    std::vector<uint8_t> occ(segs.size());
    std::vector<Hit> hits(segs.size());
    whole.Occluded(segs, occ);
    whole.Intersect(segs, hits);
    size_t occluded = 0;
    for (uint8_t o : occ)
        occluded += o;
    EXPECT_GT(occluded, segs.size() / 5);
    EXPECT_LT(occluded, segs.size() * 4 / 5);

    for (uint32_t piece : {100u, 2000u, 1000000u})
        for (uint64_t cache : {uint64_t(1), uint64_t(1) << 30}) {
            PagingOptions po;
            po.piece_triangles = piece;
            po.cache_bytes = cache;
            VisibilityScene paged;
            paged.EnablePaging(po);
            Fill(&paged, geoms);
            ASSERT_NE(paged.paged(), nullptr);
            EXPECT_EQ(paged.triangle_count(), whole.triangle_count());
            // In chunks, as the solver asks: the cache state changes between calls.
            std::vector<uint8_t> pocc(segs.size());
            std::vector<Hit> phits(segs.size());
            for (size_t lo = 0; lo < segs.size(); lo += 500) {
                const size_t n = std::min<size_t>(500, segs.size() - lo);
                paged.Occluded(std::span(segs).subspan(lo, n), std::span(pocc).subspan(lo, n));
                paged.Intersect(std::span(segs).subspan(lo, n), std::span(phits).subspan(lo, n));
            }
            EXPECT_EQ(pocc, occ) << "pieces of " << piece << ", cache " << cache;
            size_t differ = 0;
            for (size_t i = 0; i < segs.size(); ++i) {
                const Hit &a = hits[i], &b = phits[i];
                ASSERT_EQ(a.geom_id == kNoHit, b.geom_id == kNoHit) << i;
                ASSERT_TRUE(Near(a.t, b.t, std::abs(a.t))) << i << ": t " << a.t << " vs " << b.t;
                // Ties too: the lowest (geometry, primitive) at equal t in both.
                differ += a.geom_id != b.geom_id || a.prim_id != b.prim_id || !SameHitValues(a, b);
            }
            EXPECT_EQ(differ, 0u);
            const PagingStats st = paged.paged()->stats();
            std::printf("pieces of %u (%llu, largest %llu), cache %llu: %llu requests, %llu hits, "
                        "%llu loads, %llu rentals, %llu triangles built, %.2f rays per segment\n",
                        piece, (unsigned long long)st.pieces, (unsigned long long)st.largest_piece,
                        (unsigned long long)cache, (unsigned long long)st.requests,
                        (unsigned long long)st.hits, (unsigned long long)st.loads,
                        (unsigned long long)st.rentals, (unsigned long long)st.built_triangles,
                        double(st.rays) / double(st.segments));
            EXPECT_LE(st.largest_piece, piece);
            EXPECT_EQ(st.requests, st.hits + st.loads + st.rentals);  // one thread
            if (piece == 100u) {
                EXPECT_GT(st.pieces, 50u);
                // Routing by the octree's leaves: a segment meets a few pieces, not all.
                EXPECT_LT(double(st.rays) / double(st.segments), 0.25 * double(st.pieces));
            }
            if (cache == 1 && st.pieces > 1) {
                EXPECT_GT(st.loads + st.rentals, st.pieces);  // a one-piece cache rebuilds
            }
            if (cache > 1) {
                EXPECT_LE(st.loads, st.pieces);  // bought once, then resident
            }
        }
}

// Every triangle of a bumpy grid twice (a scrambled copy after the originals, as a
// clustered proxy can hold): a ray meets both copies at the same t, and the hit is the
// lower-numbered copy, in one scene as in pieces of any size (Embree alone commits the one
// its BVH meets last, which differs between the whole scene and the pieces).
TEST(PagedVisibility, ClosestHitTiesGoToTheLowestTriangle) {
    constexpr uint32_t n = 40;  // quads per side, two triangles each
    Geometry g;
    for (uint32_t j = 0; j <= n; ++j)
        for (uint32_t i = 0; i <= n; ++i)
            g.p.insert(g.p.end(), {float(i), float(j), 0.3f * std::sin(0.7f * float(i * j))});
    std::vector<std::array<uint32_t, 3>> tris;
    for (uint32_t j = 0; j < n; ++j)
        for (uint32_t i = 0; i < n; ++i) {
            const uint32_t a = j * (n + 1) + i;
            tris.push_back({a, a + 1, a + n + 2});
            tris.push_back({a, a + n + 2, a + n + 1});
        }
    std::mt19937 rng(5);
    std::shuffle(tris.begin(), tris.end(), rng);
    const uint32_t originals = uint32_t(tris.size());
    std::vector<std::array<uint32_t, 3>> copies = tris;
    std::shuffle(copies.begin(), copies.end(), rng);
    tris.insert(tris.end(), copies.begin(), copies.end());
    for (const auto& t : tris)
        g.t.insert(g.t.end(), t.begin(), t.end());
    // Slanted rays down onto the grid.
    std::vector<Segment> segs;
    std::uniform_real_distribution<float> f(1, float(n) - 1), e(-0.2f, 0.2f);
    for (int k = 0; k < 8000; ++k)
        segs.push_back(Segment{f(rng), f(rng), 2.f, 0.f, e(rng), e(rng), -1.f, 4.f});
    VisibilityScene whole;
    Fill(&whole, {g});
    std::vector<Hit> hits(segs.size());
    whole.Intersect(segs, hits);
    for (size_t k = 0; k < segs.size(); ++k) {
        ASSERT_NE(hits[k].geom_id, kNoHit) << k;
        ASSERT_LT(hits[k].prim_id, originals) << k;  // the original, never its copy
    }
    for (uint32_t piece : {7u, 100u, 1000u}) {
        PagingOptions po;
        po.piece_triangles = piece;
        po.cache_bytes = 1;  // rents and buys alike
        VisibilityScene paged;
        paged.EnablePaging(po);
        Fill(&paged, {g});
        std::vector<Hit> phits(segs.size());
        for (size_t lo = 0; lo < segs.size(); lo += 100) {
            const size_t m = std::min<size_t>(100, segs.size() - lo);
            paged.Intersect(std::span(segs).subspan(lo, m), std::span(phits).subspan(lo, m));
        }
        for (size_t k = 0; k < segs.size(); ++k) {
            ASSERT_EQ(phits[k].prim_id, hits[k].prim_id) << "pieces of " << piece << ", " << k;
            ASSERT_EQ(phits[k].geom_id, hits[k].geom_id);
            ASSERT_TRUE(Near(phits[k].t, hits[k].t, std::abs(hits[k].t)))
                << phits[k].t << " vs " << hits[k].t;
        }
    }
}

TEST(PagedVisibility, ConcurrentQueriesMatchSerial) {
    const auto geoms = Scene();
    const std::vector<Segment> segs = Segments(30000, 12);
    PagingOptions po;
    po.piece_triangles = 500;
    po.cache_bytes = 3 * 500 * kPieceBytesPerTriangle;  // three pieces of the ~20
    VisibilityScene paged;
    paged.EnablePaging(po);
    Fill(&paged, geoms);
    VisibilityScene whole;
    Fill(&whole, geoms);
    std::vector<uint8_t> serial(segs.size()), parallel(segs.size()), tasks(segs.size());
    whole.Occluded(segs, serial);
    paged.OccludedParallel(segs, parallel);
    EXPECT_EQ(serial, parallel);
    TaskGroup group;
    const size_t half = segs.size() / 2;
    group.Run([&] {
        paged.Occluded(std::span(segs).subspan(0, half), std::span(tasks).subspan(0, half));
    });
    group.Run(
        [&] { paged.Occluded(std::span(segs).subspan(half), std::span(tasks).subspan(half)); });
    group.Wait();
    EXPECT_EQ(serial, tasks);
}

TEST(PagedVisibility, ResidentPiecesStayUnderTheCache) {
    const auto geoms = Scene();
    const std::vector<Segment> segs = Segments(5000, 4);
    PagingOptions po;
    po.piece_triangles = 1000;
    po.cache_bytes = 2 * 1000 * kPieceBytesPerTriangle;
    VisibilityScene paged;
    paged.EnablePaging(po);
    Fill(&paged, geoms);
    const int64_t before = EmbreeMemoryBytes();
    std::vector<uint8_t> occ(segs.size());
    int64_t most = 0;
    for (size_t lo = 0; lo < segs.size(); lo += 250) {
        paged.Occluded(std::span(segs).subspan(lo, 250), std::span(occ).subspan(lo, 250));
        most = std::max(most, EmbreeMemoryBytes() - before);
    }
    const PagingStats st = paged.paged()->stats();
    ASSERT_GT(st.pieces, 4u);
    // Two resident pieces and the one being built, at Embree's real cost per triangle.
    std::printf("Embree bytes beyond the start: at most %lld (cache %llu)\n", (long long)most,
                (unsigned long long)po.cache_bytes);
    EXPECT_LE(most, int64_t(3 * 1000 * kPieceBytesPerTriangle));
}

// Paged only where the scene cannot fit: ingest sizes the visibility mesh to the 64 MiB
// share (full mesh at 56 B per triangle, clustered proxy at 100 B), which fits the Embree
// cap from --memory 256M up. A 1M-triangle full mesh at the default budget must not be
// paged (the paged path costs 3x the CPU; a 100 B estimate for it paged the 1M rock).
TEST(PagedVisibilityChoice, OnlyWhenTheSceneExceedsHalfTheEmbreeCap) {
    constexpr uint64_t MiB = uint64_t(1) << 20;
    stream::Manifest full;
    full.proxy_triangles = 1'000'000;  // the full mesh (no clustering cell)
    EXPECT_FALSE(VisibilityIsPaged(full, MemoryBudget(1024 * MiB)));
    EXPECT_FALSE(VisibilityIsPaged(full, MemoryBudget(256 * MiB)));
    EXPECT_TRUE(VisibilityIsPaged(full, MemoryBudget(128 * MiB)));
    stream::Manifest proxy;
    proxy.proxy_triangles = 670'000;  // the largest proxy ingest makes
    proxy.proxy_cell_size = 0.01;
    EXPECT_FALSE(VisibilityIsPaged(proxy, MemoryBudget(256 * MiB)));
    EXPECT_TRUE(VisibilityIsPaged(proxy, MemoryBudget(128 * MiB)));
}

// The full BVH (faster, ~30 % more Embree memory) only for scenes that fit the visibility
// share at 3x the ingest's estimate, and the same choice at every budget from 256M up, so
// that a bake's bytes do not follow --memory there.
TEST(CompactBvhChoice, FullForTheSharedScansCompactForLargeOrPagedScenes) {
    constexpr uint64_t MiB = uint64_t(1) << 20;
    stream::Manifest igea;
    igea.proxy_triangles = 268'686;  // the largest shared scan, full mesh
    for (uint64_t budget : {256 * MiB, 1024 * MiB, 8192 * MiB})
        EXPECT_FALSE(VisibilityIsCompact(igea, MemoryBudget(budget))) << budget;
    stream::Manifest big;
    big.proxy_triangles = 1'000'000;
    for (uint64_t budget : {256 * MiB, 1024 * MiB, 8192 * MiB})
        EXPECT_TRUE(VisibilityIsCompact(big, MemoryBudget(budget))) << budget;
    stream::Manifest proxy;
    proxy.proxy_triangles = 670'000;
    proxy.proxy_cell_size = 0.01;
    EXPECT_TRUE(VisibilityIsCompact(proxy, MemoryBudget(1024 * MiB)));
    // Paged (under 256M): compact, as the pieces are sized.
    stream::Manifest paged;
    paged.proxy_triangles = 1'000'000;
    ASSERT_TRUE(VisibilityIsPaged(paged, MemoryBudget(128 * MiB)));
    EXPECT_TRUE(VisibilityIsCompact(paged, MemoryBudget(128 * MiB)));
}

}  // namespace
}  // namespace mebake::solve
