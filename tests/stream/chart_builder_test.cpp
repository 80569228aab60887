// A brick's charts: what BuildBrickCharts hands back to the ingest, which keeps it for
// every brick until the chart pass ends.
#include "core/parallel.h"
#include "io/byte_stream.h"
#include "io/mesh_format.h"
#include "stream/bricks.h"
#include "stream/chart_builder.h"
#include "stream/spill.h"
#include "stream/tile.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace mebake::stream {
namespace {

namespace fs = std::filesystem;

// A wavy n x n grid of quads (2 n^2 triangles) as an ASCII PLY.
void WriteGrid(const std::string& path, int n, double amplitude = 0.05) {
    std::ofstream out(path);
    out << "ply\nformat ascii 1.0\nelement vertex " << (n + 1) * (n + 1)
        << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << 2 * n * n
        << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            out << double(i) / n << ' ' << double(j) / n << ' '
                << amplitude * std::sin(6.0 * i / n) * std::cos(5.0 * j / n) << '\n';
    auto id = [n](int i, int j) { return j * (n + 1) + i; };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            out << "3 " << id(i, j) << ' ' << id(i + 1, j) << ' ' << id(i + 1, j + 1) << '\n';
            out << "3 " << id(i, j) << ' ' << id(i + 1, j + 1) << ' ' << id(i, j + 1) << '\n';
        }
}

// A fresh work directory (with tiles/ and bricks/) named for the test and the process.
fs::path WorkDir(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir / "tiles");
    fs::create_directories(dir / "bricks");
    return dir;
}

// Spills the PLY at ply into dir, as the ingest's first pass does.
SpillResult SpillPly(const fs::path& dir, const std::string& ply) {
    Spill spill(dir.string(), size_t(1) << 20);
    auto in = io::InputStream::Open(ply);
    io::ReadMesh(*in, io::MeshFormat::Ply, spill.BeginInput(ply));
    return spill.Finish();
}

TEST(ChartBuilder, BrickResultKeepsNoPerVertexData) {
    const fs::path dir = WorkDir("mebake_chart_builder");
    const std::string ply = (dir / "grid.ply").string();
    WriteGrid(ply, 40);  // 3200 triangles
    const SpillResult sr = SpillPly(dir, ply);
    BinOptions bopt;
    bopt.max_faces = 1000;  // several bricks, so each has vertices on a cut
    const BrickPlan plan = BinFaces(dir.string(), sr, bopt);
    ASSERT_GE(plan.bricks.size(), 2u);

    std::vector<uint8_t> on_cut;
    const TriMesh brick = LoadBrick(dir.string(), 0, size_t(1) << 20, &on_cut);
    ASSERT_GT(brick.triangles.size(), 0u);
    ASSERT_GT(std::count(on_cut.begin(), on_cut.end(), uint8_t(1)), 0);  // what the repair flags

    const BrickResult r = BuildBrickCharts(dir.string(), 0, ChartBuildOptions{});
    EXPECT_GT(r.charts.size(), 0u);
    EXPECT_EQ(r.repair.output_triangles, brick.triangles.size());
    // The ingest keeps every brick's result to the end of the chart pass: per-vertex data
    // in it would grow with the mesh (the cut flags did: 50 MB at 100M triangles).
    EXPECT_TRUE(r.repair.vertex_on_cut.empty());
    EXPECT_EQ(r.repair.vertex_on_cut.capacity(), 0u);
    fs::remove_all(dir);
}

// The charts of one brick are built in parallel (chart_builder.cpp, BuildFromRoot): the
// tiles, their order and every record must not depend on the thread count, also when
// charts are split (a distortion bound no wavy chart meets).
TEST(ChartBuilder, ABricksChartsDoNotDependOnTheThreadCount) {
    const fs::path dir = WorkDir("mebake_chart_threads");
    const std::string ply = (dir / "grid.ply").string();
    WriteGrid(ply, 30, 0.3);
    const SpillResult sr = SpillPly(dir, ply);
    ASSERT_EQ(BinFaces(dir.string(), sr, BinOptions{}).bricks.size(), 1u);
    ChartBuildOptions o;
    o.merge_charts = false;
    o.max_distortion = 1e-4;
    o.max_chart_vertices = 300;  // several charts from the segmentation
    struct Built {
        BrickResult result;
        std::vector<std::string> tiles;  // each tile's bytes, in order
    };
    auto build = [&](int threads) {
        ThreadLimit limit(threads);
        Built b;
        b.result = BuildBrickCharts(dir.string(), 0, o);
        for (const std::string& path : b.result.tile_files) {
            std::ifstream in(path, std::ios::binary);
            b.tiles.emplace_back(std::istreambuf_iterator<char>(in),
                                 std::istreambuf_iterator<char>());
            fs::remove(path);
        }
        return b;
    };
    const Built one = build(1), two = build(2);
    ASSERT_GE(one.result.charts.size(), 4u);
    ASSERT_GT(one.result.splits, 0u) << "the test needs charts that are split";
    EXPECT_EQ(one.result.splits, two.result.splits);
    ASSERT_EQ(one.result.charts.size(), two.result.charts.size());
    ASSERT_EQ(one.tiles.size(), one.result.charts.size());
    EXPECT_EQ(one.result.tile_files, two.result.tile_files);
    for (size_t c = 0; c < one.result.charts.size(); ++c) {
        EXPECT_EQ(one.result.charts[c].triangles, two.result.charts[c].triangles) << c;
        EXPECT_EQ(one.result.charts[c].scale, two.result.charts[c].scale) << c;
        EXPECT_TRUE(one.tiles[c] == two.tiles[c]) << "tile " << c << " differs";
    }
    fs::remove_all(dir);
}

// Half a cylinder, radius 1 and length pi (n x n quads): the segmentation's 60-degree
// normal cone cuts it into several charts, which merge (it is developable) into squares
// of about pi a side.
void WriteHalfCylinder(const std::string& path, int n) {
    constexpr double kPi = 3.14159265358979323846;
    std::ofstream out(path);
    out << "ply\nformat ascii 1.0\nelement vertex " << (n + 1) * (n + 1)
        << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << 2 * n * n
        << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const double a = kPi * i / n;
            out << std::cos(a) << ' ' << kPi * j / n << ' ' << std::sin(a) << '\n';
        }
    auto id = [n](int i, int j) { return j * (n + 1) + i; };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            out << "3 " << id(i, j) << ' ' << id(i + 1, j + 1) << ' ' << id(i + 1, j) << '\n';
            out << "3 " << id(i, j) << ' ' << id(i, j + 1) << ' ' << id(i + 1, j + 1) << '\n';
        }
}

// With merge_horizon_cells a union's geometry image follows its light-map texels up to
// union_geometry_resolution (the other charts' cap, max_geometry_resolution, made a
// merged 512-texel chart's geometry samples 4 texels wide: the turbine blade's thin edges
// came out 45-74 % dark); a chart that is not a union keeps the common cap.
TEST(ChartBuilder, AUnionsGeometryFollowsItsTexels) {
    const fs::path dir = WorkDir("mebake_union_geometry");
    const std::string ply = (dir / "cyl.ply").string();
    WriteHalfCylinder(ply, 40);
    const SpillResult sr = SpillPly(dir, ply);
    ASSERT_EQ(BinFaces(dir.string(), sr, BinOptions{}).bricks.size(), 1u);

    ChartBuildOptions o;
    o.texel_size = 3.14159 / 200;  // a union of pi a side: 256 texels
    o.max_geometry_resolution = 32;
    o.union_geometry_resolution = 128;
    struct Chart {
        uint32_t texels = 0, geometry = 0, emitter = 0;
        double scale = 0;
    };
    auto charts = [&](bool horizon_cells, bool merge) {
        o.merge_horizon_cells = horizon_cells;
        o.merge_charts = merge;
        const BrickResult r = BuildBrickCharts(dir.string(), 0, o);
        std::vector<Chart> res;
        for (size_t c = 0; c < r.charts.size(); ++c) {
            const ChartTile t = ReadTile(r.tile_files[c], TileParts::GeometryImage);
            res.push_back({r.charts[c].resolution, t.geometry.resolution,
                           t.meta.emitter_resolution, r.charts[c].scale});
        }
        return res;
    };
    const auto apart = charts(true, false);
    ASSERT_GE(apart.size(), 2u);  // the normal cone cut it
    double largest_part = 0;
    for (const Chart& c : apart) {
        EXPECT_EQ(c.geometry, std::min(c.texels, 32u));
        EXPECT_EQ(c.emitter, 0u) << "a chart that is not a union keeps the solver's rule";
        largest_part = std::max(largest_part, c.scale);
    }
    const auto merged = charts(true, true);
    ASSERT_LT(merged.size(), apart.size());
    uint32_t finest = 0, finest_emitter = 0;
    for (const Chart& c : merged) {
        EXPECT_EQ(c.geometry, std::min(c.texels, 128u)) << "a union's geometry follows its texels";
        finest = std::max(finest, c.geometry);
        // Its emitter samples are about as small as its parts' (32 a side each: within a
        // factor sqrt(2)), and no finer than its geometry.
        if (c.emitter != 0) {
            EXPECT_GT(c.emitter, o.emitter_samples);
            EXPECT_LE(c.emitter, c.geometry);
            EXPECT_LE(c.scale / c.emitter, std::sqrt(2.0) * largest_part / o.emitter_samples);
        }
        finest_emitter = std::max(finest_emitter, c.emitter);
    }
    EXPECT_GT(finest, 32u);
    // The normal cone cut the half cylinder into strips along its axis, each in a square as
    // large as the union's: the union's samples are its parts' size already.
    EXPECT_EQ(finest_emitter, 0u) << "a union of strips needs no finer emitter samples";
    fs::remove_all(dir);
}

// A union's emitter samples: as many a side as keep them as small as its parts' mean sample
// (the nearest power of two, so within a factor sqrt(2)), at most its geometry's; 0 (the
// solver's own 32 a side) when that is fine enough.
TEST(ChartBuilder, UnionEmitterResolutionKeepsItsPartsSampleSize) {
    ChartBuildOptions o;  // 32 samples a side per chart
    EXPECT_EQ(UnionEmitterResolution(4, 1, 256, o), 128u);   // four times the parts' side
    EXPECT_EQ(UnionEmitterResolution(3, 1, 256, o), 128u);   // 96: nearer 128 than 64
    EXPECT_EQ(UnionEmitterResolution(2.5, 1, 256, o), 64u);  // 80: nearer 64
    EXPECT_EQ(UnionEmitterResolution(4, 1, 64, o), 64u);     // the geometry's cap
    EXPECT_EQ(UnionEmitterResolution(2, 1.5, 256, o), 0u);   // 42.7: 32 is near enough
    EXPECT_EQ(UnionEmitterResolution(2, 2, 256, o), 0u);     // not larger than its parts
    EXPECT_EQ(UnionEmitterResolution(2, 0, 256, o), 0u);     // parts unknown
    EXPECT_EQ(UnionEmitterResolution(4, 1, 32, o), 0u);      // geometry no finer than 32
    o.emitter_samples = 8;
    EXPECT_EQ(UnionEmitterResolution(4, 1, 256, o), 32u);
}

}  // namespace
}  // namespace mebake::stream
