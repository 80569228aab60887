#include "io/mesh_stats.h"

#include "core/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <unistd.h>
#include <vector>

namespace mebake::io {
namespace {

// The sink's spill block (1024 positions): cache sizes below are counted in these.
constexpr size_t kSlot = size_t(12) << 10;

// A mesh held whole, fed to a sink in chosen batch sizes and orders, like a reader would.
struct TestMesh {
    std::vector<Vec3f> positions;
    std::vector<std::vector<uint64_t>> faces;

    void SendVertices(MeshSink& sink, size_t batch) const {
        VertexBatch vb;
        for (size_t i = 0; i < positions.size(); i += batch) {
            vb.Clear();
            vb.first = i;
            for (size_t k = i; k < std::min(positions.size(), i + batch); ++k)
                vb.position.push_back(positions[k]);
            sink.Vertices(vb);
        }
    }
    void SendFaces(MeshSink& sink, size_t batch, size_t begin = 0,
                   size_t end = std::numeric_limits<size_t>::max()) const {
        FaceBatch fb;
        end = std::min(end, faces.size());
        for (size_t i = begin; i < end; i += batch) {
            fb.Clear();
            fb.first = i;
            for (size_t k = i; k < std::min(end, i + batch); ++k) {
                fb.size.push_back(uint32_t(faces[k].size()));
                fb.index.insert(fb.index.end(), faces[k].begin(), faces[k].end());
            }
            sink.Faces(fb);
        }
    }
    MeshHeader Header() const {
        MeshHeader h;
        h.source = "test";
        h.vertex_count = positions.size();
        h.face_count = faces.size();
        return h;
    }
    MeshSummary Summary() const {
        MeshSummary s;
        s.vertex_count = positions.size();
        s.face_count = faces.size();
        return s;
    }
};

// Unit square quad, triangles, a collinear and a repeated-index face, a pentagon, an
// unreferenced vertex and a NaN one.
TestMesh SmallMesh() {
    TestMesh m;
    float nan = std::numeric_limits<float>::quiet_NaN();
    m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0},  {0, 1, 0},
                   {2, 0, 0}, {5, 5, 5}, {0, 0, -1}, {nan, 0, 0}};
    m.faces = {
        {0, 1, 2},        // area 0.5
        {0, 1, 2, 3},     // area 1
        {0, 1, 4},        // collinear: zero area
        {0, 0, 1},        // repeated index: degenerate
        {0, 3, 6},        // area 0.5
        {0, 1, 2, 3, 6},  // fan: 0.5 + 0.5 + 0.5
    };
    return m;
}

void ExpectSmallStats(const MeshStats& s) {
    EXPECT_EQ(s.header.source, "test");
    EXPECT_EQ(s.summary.vertex_count, 8u);
    EXPECT_EQ(s.summary.face_count, 6u);
    EXPECT_EQ(s.face_sizes, (std::map<uint32_t, uint64_t>{{3, 4}, {4, 1}, {5, 1}}));
    EXPECT_EQ(s.triangles, 9u);
    EXPECT_EQ(s.degenerate_faces, 1u);
    EXPECT_EQ(s.zero_area_faces, 1u);
    EXPECT_EQ(s.unreferenced_vertices, 2u);  // 5 and the NaN one
    EXPECT_DOUBLE_EQ(s.surface_area, 3.5);
    EXPECT_EQ(s.bbox_min, Vec3d(0, 0, -1));  // NaN position left out
    EXPECT_EQ(s.bbox_max, Vec3d(5, 5, 5));
    EXPECT_GE(s.read_seconds, 0.0);
}

TEST(MeshStats, SmallMeshVerticesFirst) {
    TestMesh m = SmallMesh();
    MeshStatsSink sink;
    sink.Begin(m.Header());
    m.SendVertices(sink, 3);
    m.SendFaces(sink, 4);
    sink.End(m.Summary());
    ExpectSmallStats(sink.stats());
}

// A PLY with the face element first: areas settle in End().
TEST(MeshStats, SmallMeshFacesFirst) {
    TestMesh m = SmallMesh();
    MeshStatsSink sink;
    sink.Begin(m.Header());
    m.SendFaces(sink, 2);
    m.SendVertices(sink, 5);
    sink.End(m.Summary());
    ExpectSmallStats(sink.stats());
}

TEST(MeshStats, SinkIsReusableAfterEnd) {
    TestMesh m = SmallMesh();
    MeshStatsSink sink;
    for (int pass = 0; pass < 2; ++pass) {
        sink.Begin(m.Header());
        m.SendVertices(sink, 8);
        m.SendFaces(sink, 6);
        sink.End(m.Summary());
        ExpectSmallStats(sink.stats());
    }
}

TEST(MeshStats, EmptyMesh) {
    MeshStatsSink sink;
    sink.Begin(MeshHeader{});
    sink.End(MeshSummary{});
    const MeshStats& s = sink.stats();
    EXPECT_EQ(s.triangles, 0u);
    EXPECT_EQ(s.unreferenced_vertices, 0u);
    EXPECT_EQ(s.surface_area, 0.0);
    EXPECT_TRUE(s.face_sizes.empty());
}

// A w x h grid of unit-spaced vertices in the z=0 plane, split into triangles; every
// `stride`-th quad row also gets a hexagon fan over its cell (7 corners with a repeat).
TestMesh Grid(int w, int h) {
    TestMesh m;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            m.positions.push_back({float(x), float(y), 0.0f});
    auto id = [w](int x, int y) {
        return uint64_t(y) * uint64_t(w) + uint64_t(x);
    };
    for (int y = 0; y + 1 < h; ++y) {
        for (int x = 0; x + 1 < w; ++x) {
            m.faces.push_back({id(x, y), id(x + 1, y), id(x + 1, y + 1)});
            m.faces.push_back({id(x, y), id(x + 1, y + 1), id(x, y + 1)});
        }
    }
    return m;
}

// Shuffles faces deterministically (a fixed LCG), so look-ups jump across the spill.
void Shuffle(std::vector<std::vector<uint64_t>>& faces) {
    uint64_t s = 12345;
    for (size_t i = faces.size(); i > 1; --i) {
        s = s * 6364136223846793005ULL + 1442695040888963407ULL;
        std::swap(faces[i - 1], faces[size_t((s >> 33) % i)]);
    }
}

MeshStats CollectStats(const TestMesh& m, size_t cache_bytes, size_t vbatch, size_t fbatch,
                       const std::string& dir) {
    MeshStatsSink sink(dir, cache_bytes);
    sink.Begin(m.Header());
    m.SendVertices(sink, vbatch);
    m.SendFaces(sink, fbatch);
    sink.End(m.Summary());
    return sink.stats();
}

void ExpectSame(const MeshStats& a, const MeshStats& b) {
    EXPECT_EQ(a.face_sizes, b.face_sizes);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.degenerate_faces, b.degenerate_faces);
    EXPECT_EQ(a.zero_area_faces, b.zero_area_faces);
    EXPECT_EQ(a.unreferenced_vertices, b.unreferenced_vertices);
    EXPECT_EQ(a.surface_area, b.surface_area);  // same order of summation: bit-identical
    EXPECT_EQ(a.bbox_min, b.bbox_min);
    EXPECT_EQ(a.bbox_max, b.bbox_max);
}

class MeshStatsSpill : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = std::filesystem::path(::testing::TempDir()) /
               ("mesh_stats_" + std::to_string(::getpid()));
        std::filesystem::create_directories(dir_);
    }
    void TearDown() override {
        // The spill files are unlinked at creation: nothing may be left behind.
        EXPECT_TRUE(std::filesystem::is_empty(dir_));
        std::filesystem::remove_all(dir_);
    }
    std::filesystem::path dir_;
};

TEST_F(MeshStatsSpill, TinyCacheMatchesLargeCache) {
    // 200 x 150 = 30000 vertices: 30 spill blocks; 2 cache slots force evictions.
    TestMesh m = Grid(200, 150);
    Shuffle(m.faces);
    m.faces.push_back({0, 1, 2});       // collinear along the first row
    m.faces.push_back({0, 29999, 0});   // degenerate across the whole spill
    m.positions.push_back({-3, 7, 2});  // unreferenced
    MeshStats big = CollectStats(m, size_t(1) << 30, 4096, 65536, dir_.string());
    MeshStats tiny = CollectStats(m, 1, 1000, 777, dir_.string());
    MeshStats mid = CollectStats(m, 5 * kSlot, 65536, 1 << 12, dir_.string());
    ExpectSame(big, tiny);
    ExpectSame(big, mid);
    EXPECT_EQ(big.triangles, uint64_t(2 * 199 * 149 + 2));
    EXPECT_EQ(big.zero_area_faces, 1u);
    EXPECT_EQ(big.degenerate_faces, 1u);
    EXPECT_EQ(big.unreferenced_vertices, 1u);
    EXPECT_NEAR(big.surface_area, 199.0 * 149.0, 1e-9);
    EXPECT_EQ(big.bbox_min, Vec3d(-3, 0, 0));
    EXPECT_EQ(big.bbox_max, Vec3d(199, 149, 2));
}

// Faces in file order touch two or three blocks per batch: the prefetch path, loading
// runs of blocks and pinning them while the cache evicts.
TEST_F(MeshStatsSpill, PrefetchPathWithEviction) {
    TestMesh m = Grid(300, 200);  // 60000 vertices, 59 blocks
    // Each batch also names vertex 0 and the last one, so the pinned set spans the spill.
    for (size_t f = 0; f < m.faces.size(); f += 5000)
        m.faces[f] = {0, 59999, 30000};
    MeshStats ref = CollectStats(m, size_t(1) << 30, 65536, 65536, dir_.string());
    for (size_t slots : {2, 4, 6, 8, 12, 16}) {
        for (size_t batch : {300, 1000, 2999, 5000}) {
            SCOPED_TRACE(testing::Message() << slots << " slots, face batch " << batch);
            ExpectSame(ref, CollectStats(m, slots * kSlot, 7000, batch, dir_.string()));
        }
    }
}

TEST_F(MeshStatsSpill, FacesFirstWithSpill) {
    TestMesh m = Grid(200, 150);  // 59102 faces: 1.9 MB deferred
    MeshStats ref = CollectStats(m, size_t(1) << 30, 4096, 4096, dir_.string());
    MeshStatsSink sink(dir_.string(), 1);
    sink.Begin(m.Header());
    m.SendFaces(sink, 5000);  // > 1 MiB of deferred faces: goes through the file
    m.SendVertices(sink, 3000);
    sink.End(m.Summary());
    ExpectSame(ref, sink.stats());
    EXPECT_NEAR(ref.surface_area, 199.0 * 149.0, 1e-9);
}

// OBJ-like: faces after each vertex batch, naming the vertices read so far.
TEST_F(MeshStatsSpill, InterleavedLikeObj) {
    TestMesh m = Grid(100, 100);
    MeshStats ref = CollectStats(m, size_t(1) << 30, 65536, 65536, dir_.string());
    MeshStatsSink sink(dir_.string(), 3 * kSlot);
    sink.Begin(m.Header());
    VertexBatch vb;
    size_t next_face = 0;
    for (size_t row = 0; row < 100; ++row) {
        vb.Clear();
        vb.first = row * 100;
        for (size_t x = 0; x < 100; ++x)
            vb.position.push_back(m.positions[row * 100 + x]);
        sink.Vertices(vb);
        // Faces of the quad row that ends on this vertex row.
        size_t end = row == 0 ? 0 : row * 99 * 2;
        m.SendFaces(sink, 50, next_face, end);
        next_face = end;
    }
    sink.End(m.Summary());
    ExpectSame(ref, sink.stats());
}

TEST_F(MeshStatsSpill, DeferredFaceNamingMissingVertexIsAnInputError) {
    TestMesh m = SmallMesh();
    m.faces.push_back({0, 1, 99});
    MeshStatsSink sink(dir_.string());
    sink.Begin(m.Header());
    m.SendFaces(sink, 10);
    m.SendVertices(sink, 10);
    EXPECT_THROW(sink.End(m.Summary()), Error);
}

TEST(MeshStats, UnwritableTempDirIsAnIoError) {
    // 100K vertices (1.2 MB) through the smallest cache (4 pages of 64 KiB): pages spill.
    TestMesh m = Grid(400, 250);
    MeshStatsSink sink("/nonexistent/mebake-stats-dir", 0);
    sink.Begin(m.Header());
    try {
        m.SendVertices(sink, 100000);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Io);
        EXPECT_NE(std::string(e.what()).find("/nonexistent/mebake-stats-dir"), std::string::npos);
    }
}

}  // namespace
}  // namespace mebake::io
