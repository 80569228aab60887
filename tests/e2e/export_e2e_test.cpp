// `mebake export` and `mebake render` run as a user would, on data/samples/terrain.ply:
// ingest, a short solve, every export output, a render; then the files are read back
// (EXR, PNG, PLY, .glb through the Khronos validator when installed) and the refusals
// (unsolved directory, existing output without --force) give usage errors.
#include "support/gltf_validate.h"
#include "io/byte_stream.h"
#include "io/exr_writer.h"
#include "io/mesh_format.h"
#include "io/png_writer.h"
#include "run.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <unistd.h>

namespace mebake {
namespace {

namespace fs = std::filesystem;

using e2e::Mebake;

struct Count : io::MeshSink {
    uint64_t vertices = 0, faces = 0;
    bool colors = false;
    void Begin(const io::MeshHeader& h) override { colors = h.has_colors; }
    void Vertices(const io::VertexBatch& b) override { vertices += b.size(); }
    void Faces(const io::FaceBatch& b) override { faces += b.count(); }
    void End(const io::MeshSummary&) override {}
};

class ExportE2E : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        // A command missing from the CLI is a regression: every test of the suite fails.
        help_ok_ = Mebake("export --help > /dev/null") == 0 && Mebake("render --help > /dev/null") == 0;
        dir_ = (fs::temp_directory_path() / ("mebake-e2e-export-" + std::to_string(::getpid())))
                   .string();
        fs::remove_all(dir_);
        fs::create_directories(dir_);
        const std::string mesh = std::string(MEBAKE_SOURCE_DIR) + "/data/samples/terrain.ply";
        ok_ = Mebake("-q ingest '" + mesh + "' -o '" + dir_ +
                     "/t.mebake' --lightmap-resolution 128") == 0 &&
              Mebake("-q solve '" + dir_ + "/t.mebake' --max-bounces 0") == 0;
    }
    static void TearDownTestSuite() {
        if (!dir_.empty())
            fs::remove_all(dir_);
    }
    void SetUp() override {
        ASSERT_TRUE(help_ok_) << "`mebake export --help` or `mebake render --help` failed";
        ASSERT_TRUE(ok_) << "ingest or solve failed";
    }
    std::string Bake() const { return "'" + dir_ + "/t.mebake'"; }
    std::string Out(const std::string& name) const { return dir_ + "/" + name; }

    static std::string dir_;
    static bool ok_, help_ok_;
};
std::string ExportE2E::dir_;
bool ExportE2E::ok_ = false;
bool ExportE2E::help_ok_ = false;

TEST_F(ExportE2E, EveryOutput) {
    ASSERT_EQ(Mebake("-q export " + Bake() + " --lightmap '" + Out("lm.exr") + "' --irradiance '" +
                     Out("e.exr") + "' --mesh '" + Out("m.glb") + "' --vertex-colors '" +
                     Out("vc.ply") + "' --stats '" + Out("s.json") + "'"),
              0);
    std::ifstream sf(Out("s.json"));
    const auto stats = nlohmann::json::parse(sf);
    EXPECT_GE(stats["charts"].get<int>(), 1);
    EXPECT_GT(stats["atlas"]["fill"].get<double>(), 0.1);
    // Every chart border of a connected terrain is a seam edge shared by two charts.
    if (stats["charts"].get<int>() > 1)
        EXPECT_GT(stats["seams"]["edges"].get<int>(), 0);
    else
        EXPECT_EQ(stats["seams"]["edges"].get<int>(), 0);

    const io::ExrImage lm = io::ReadExr(Out("lm.exr"));
    const auto& page = stats["atlas"]["pages"][0];
    EXPECT_EQ(lm.width, page["width"].get<int>());
    ASSERT_GE(lm.Channel("G"), 0);
    double sum = 0;
    for (int y = 0; y < lm.height; ++y)
        for (int x = 0; x < lm.width; ++x) {
            const float g = lm.At(x, y, lm.Channel("G"));
            ASSERT_TRUE(std::isfinite(g) && g >= 0);
            sum += g;
        }
    EXPECT_GT(sum, 0) << "a lit scene has a non-black light map";
    EXPECT_EQ(io::ReadExr(Out("e.exr")).channels.size(), 9u);

    // The terrain sample has 2601 vertices and 5000 triangles (data/samples/README.md).
    Count vc;
    auto in = io::InputStream::Open(Out("vc.ply"));
    io::ReadMesh(*in, io::MeshFormat::Ply, vc);
    EXPECT_EQ(vc.vertices, 2601u);
    EXPECT_EQ(vc.faces, 5000u);
    EXPECT_TRUE(vc.colors);

    if (auto v = testing::ValidateGltf(Out("m.glb"))) {
        EXPECT_EQ(v->exit_code, 0) << v->report;
    }
}

TEST_F(ExportE2E, RenderAndRefusals) {
    ASSERT_EQ(Mebake("-q render " + Bake() + " -o '" + Out("v.png") + "' --size 64x48"), 0);
    const io::PngImage png = io::ReadPng(Out("v.png"));
    EXPECT_EQ(png.width, 64);
    EXPECT_EQ(png.height, 48);
    // An existing output is kept unless --force.
    EXPECT_EQ(Mebake("-q render " + Bake() + " -o '" + Out("v.png") + "' --size 32x24"), 2);
    EXPECT_EQ(io::ReadPng(Out("v.png")).width, 64);
    EXPECT_EQ(Mebake("-q render " + Bake() + " -o '" + Out("v.png") + "' --size 32x24 -f"), 0);
    EXPECT_EQ(io::ReadPng(Out("v.png")).width, 32);
    EXPECT_EQ(Mebake("-q render " + Bake() + " -o '" + Out("v.exr") + "' --size 3x"), 2);
    EXPECT_EQ(Mebake("-q export " + Bake()), 2) << "nothing to export";
    // An unsolved directory.
    fs::copy(dir_ + "/t.mebake", dir_ + "/u.mebake", fs::copy_options::recursive);
    fs::remove(dir_ + "/u.mebake/solve/solution.bin");
    EXPECT_EQ(Mebake("-q export '" + dir_ + "/u.mebake' --lightmap '" + Out("u.exr") + "'"), 2);
    EXPECT_FALSE(fs::exists(Out("u.exr")));
}

}  // namespace
}  // namespace mebake
