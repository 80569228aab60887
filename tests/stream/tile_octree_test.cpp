// The triangle octree (stream/tile_octree.h) and the tiles that carry it (stream/tile.h).
#include "stream/tile_octree.h"

#include "core/error.h"
#include "io/chunk_file.h"
#include "stream/tile.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace mebake::stream {
namespace {

struct Mesh {
    std::vector<Vec3f> p;
    std::vector<std::array<uint32_t, 3>> t;
};

// A bumpy sphere of n x 2n quads (two triangles each): spatially coherent, like a scan.
Mesh Sphere(int n) {
    Mesh m;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= 2 * n; ++i) {
            const double th = M_PI * j / n, ph = M_PI * i / n;
            const double r = 1 + 0.05 * std::sin(7 * th) * std::cos(5 * ph);
            m.p.push_back(Vec3f(float(r * std::sin(th) * std::cos(ph)),
                                float(r * std::sin(th) * std::sin(ph)), float(r * std::cos(th))));
        }
    const uint32_t w = uint32_t(2 * n + 1);
    for (uint32_t j = 0; j < uint32_t(n); ++j)
        for (uint32_t i = 0; i < uint32_t(2 * n); ++i) {
            const uint32_t a = j * w + i;
            m.t.push_back({a, a + 1, a + w + 1});
            m.t.push_back({a, a + w + 1, a + w});
        }
    return m;
}

// Segment/triangle intersection in double (Moller-Trumbore), t in [t0, t1].
bool Crosses(const Vec3f& o, const Vec3f& d, float t0, float t1, const Vec3f& a, const Vec3f& b,
             const Vec3f& c) {
    const Vec3d O(o), D(d), A(a), e1 = Vec3d(b) - A, e2 = Vec3d(c) - A;
    const Vec3d p = Cross(D, e2);
    const double det = Dot(e1, p);
    if (std::fabs(det) < 1e-300)
        return false;
    const Vec3d s = O - A;
    const double u = Dot(s, p) / det;
    const Vec3d q = Cross(s, e1);
    const double v = Dot(D, q) / det, t = Dot(e2, q) / det;
    return u >= 0 && v >= 0 && u + v <= 1 && t >= t0 && t <= t1;
}

TEST(TileOctree, EveryTriangleInOneLeafInsideItsBox) {
    const Mesh m = Sphere(40);
    OctreeOptions o;
    o.leaf_triangles = 20;
    const TriangleOctree tree = BuildTriangleOctree(m.p, m.t, o);
    EXPECT_NO_THROW(CheckTriangleOctree(tree, m.t.size(), "test"));
    size_t leaves = 0;
    for (uint32_t leaf : tree.Leaves()) {
        const OctreeNode& n = tree.nodes[leaf];
        ++leaves;
        EXPECT_LE(n.count, o.leaf_triangles);  // the sphere never reaches max_depth
        for (uint32_t k = n.first; k < n.first + n.count; ++k)
            for (uint32_t v : m.t[tree.order[k]])
                for (int a = 0; a < 3; ++a) {
                    EXPECT_LE(n.lo[a], m.p[v][a]);
                    EXPECT_GE(n.hi[a], m.p[v][a]);
                }
    }
    EXPECT_GT(leaves, m.t.size() / 20);
    // Deterministic: the same input gives the same bytes.
    const TriangleOctree again = BuildTriangleOctree(m.p, m.t, o);
    ASSERT_EQ(again.nodes.size(), tree.nodes.size());
    EXPECT_EQ(0, std::memcmp(again.nodes.data(), tree.nodes.data(),
                             tree.nodes.size() * sizeof(OctreeNode)));
    EXPECT_EQ(again.order, tree.order);
    EXPECT_TRUE(BuildTriangleOctree(m.p, {}, o).empty());
}

TEST(TileOctree, SegmentQueryVisitsEveryLeafOfACrossedTriangle) {
    const Mesh m = Sphere(30);
    const TriangleOctree tree = BuildTriangleOctree(m.p, m.t, {8, 12});
    const OctreeRouter router(tree);
    std::vector<uint32_t> leaf_of(m.t.size());
    for (uint32_t leaf : tree.Leaves())
        for (uint32_t k = tree.nodes[leaf].first; k < tree.nodes[leaf].first + tree.nodes[leaf].count;
             ++k)
            leaf_of[tree.order[k]] = leaf;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> f(-1.3f, 1.3f);
    size_t crossings = 0, visited = 0;
    for (int s = 0; s < 400; ++s) {
        const Vec3f o(f(rng), f(rng), f(rng)), d(f(rng), f(rng), f(rng));
        // Also axis-parallel segments and ones through vertices (grazing the boxes).
        const Vec3f dd = s % 7 == 0 ? Vec3f(0, 0, d.z) : d;
        const Vec3f oo = s % 11 == 0 ? m.p[size_t(s) % m.p.size()] - dd * 0.5f : o;
        std::vector<uint8_t> seen(tree.nodes.size(), 0);
        router.ForEachLeafOnSegment(oo, dd, 0, 1, [&](uint32_t leaf) {
            seen[leaf] = 1;
            ++visited;
        });
        for (size_t t = 0; t < m.t.size(); ++t)
            if (Crosses(oo, dd, 0, 1, m.p[m.t[t][0]], m.p[m.t[t][1]], m.p[m.t[t][2]])) {
                ++crossings;
                EXPECT_TRUE(seen[leaf_of[t]]) << "segment " << s << " triangle " << t;
            }
    }
    EXPECT_GT(crossings, 200u);
    // The query prunes: far fewer leaves than all of them per segment.
    EXPECT_LT(visited, 400 * tree.Leaves().size() / 4);
}

TEST(TileOctree, MalformedTreesAreCorrupt) {
    const Mesh m = Sphere(10);
    const TriangleOctree good = BuildTriangleOctree(m.p, m.t, {8, 12});
    TriangleOctree t = good;
    t.order[3] = t.order[4];  // a triangle twice, another never
    EXPECT_THROW(CheckTriangleOctree(t, m.t.size(), "x"), Error);
    t = good;
    t.nodes[0].child = uint32_t(t.nodes.size());  // children out of range
    EXPECT_THROW(CheckTriangleOctree(t, m.t.size(), "x"), Error);
    t = good;
    t.nodes[1].count += 1;  // children no longer tile the root
    EXPECT_THROW(CheckTriangleOctree(t, m.t.size(), "x"), Error);
    EXPECT_THROW(CheckTriangleOctree(good, m.t.size() + 1, "x"), Error);
}

// A tile of the sphere: the octree is written with it, read back, and checked.
ChartTile SphereTile(const Mesh& m) {
    ChartTile t;
    t.position = m.p;
    t.triangles = m.t;
    for (const Vec3f& p : m.p) {
        t.normal.push_back(Normalize(p));
        t.uv.push_back(Vec2f(0.5f + 0.49f * p.x, 0.5f + 0.49f * p.y));
        t.vertex_id.push_back(t.vertex_id.size());
    }
    t.face_id.assign(m.t.size(), 0);
    t.material.assign(m.t.size(), 0);
    t.grid = BuildChartGrid(t.uv, t.triangles, 4);
    t.geometry.resolution = 1;
    t.geometry.levels.resize(1);
    t.geometry.levels[0].resize(1);
    t.geometry.BuildPyramid();
    t.meta.vertex_count = uint32_t(m.p.size());
    t.meta.triangle_count = uint32_t(m.t.size());
    t.meta.resolution = 1;
    t.meta.grid_resolution = 4;
    t.meta.scale = 1;
    return t;
}

TEST(TileOctree, TilesCarryTheirOctreeAndOldTilesAreRefused) {
    const std::string dir =
        (std::filesystem::temp_directory_path() / ("tile_octree_" + std::to_string(getpid())))
            .string();
    std::filesystem::create_directories(dir);
    const Mesh m = Sphere(12);
    const std::string path = dir + "/tile.bin";
    WriteTile(path, SphereTile(m));
    const ChartTile read = ReadTile(path, TileParts::Mesh);
    const TriangleOctree expect = BuildTriangleOctree(m.p, m.t, kTileOctree);
    ASSERT_EQ(read.octree.nodes.size(), expect.nodes.size());
    EXPECT_EQ(0, std::memcmp(read.octree.nodes.data(), expect.nodes.data(),
                             expect.nodes.size() * sizeof(OctreeNode)));
    EXPECT_EQ(read.octree.order, expect.order);
    // A version 1 tile (no octree) is refused with a message that says what to do.
    {
        io::ChunkWriter w(dir + "/old.bin", io::Tag("TILE"), 1);
        const std::vector<uint32_t> x = {1};
        w.AddArray(io::Tag("META"), 0, x);
        w.Finish();
    }
    try {
        ReadTile(dir + "/old.bin");
        ADD_FAILURE() << "a version 1 tile was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("old.bin"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("ingest the scan again"), std::string::npos)
            << e.what();
    }
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace mebake::stream
