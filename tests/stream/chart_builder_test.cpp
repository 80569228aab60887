// A brick's charts: what BuildBrickCharts hands back to the ingest, which keeps it for
// every brick until the chart pass ends.
#include "io/byte_stream.h"
#include "io/mesh_format.h"
#include "stream/bricks.h"
#include "stream/chart_builder.h"
#include "stream/spill.h"

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
void WriteGrid(const std::string& path, int n) {
    std::ofstream out(path);
    out << "ply\nformat ascii 1.0\nelement vertex " << (n + 1) * (n + 1)
        << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << 2 * n * n
        << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            out << double(i) / n << ' ' << double(j) / n << ' '
                << 0.05 * std::sin(6.0 * i / n) * std::cos(5.0 * j / n) << '\n';
    auto id = [n](int i, int j) { return j * (n + 1) + i; };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            out << "3 " << id(i, j) << ' ' << id(i + 1, j) << ' ' << id(i + 1, j + 1) << '\n';
            out << "3 " << id(i, j) << ' ' << id(i + 1, j + 1) << ' ' << id(i, j + 1) << '\n';
        }
}

TEST(ChartBuilder, BrickResultKeepsNoPerVertexData) {
    const fs::path dir =
        fs::temp_directory_path() / ("mebake_chart_builder_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir / "tiles");
    fs::create_directories(dir / "bricks");
    const std::string ply = (dir / "grid.ply").string();
    WriteGrid(ply, 40);  // 3200 triangles
    SpillResult sr;
    {
        Spill spill(dir.string(), size_t(1) << 20);
        auto in = io::InputStream::Open(ply);
        io::ReadMesh(*in, io::MeshFormat::Ply, spill.BeginInput(ply));
        sr = spill.Finish();
    }
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

}  // namespace
}  // namespace mebake::stream
