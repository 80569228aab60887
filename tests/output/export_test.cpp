// Mesh and vertex-colour export on the two-chart fixture: the .glb (layout, counts, atlas
// uvs, embedded light map, Khronos validator), PLY/OBJ with light-map uvs (UDIM offsets
// over several pages), and the per-vertex colour PLY (input order and count, averaging on
// shared vertices, black unreferenced vertices, hole fills dropped).
#include "support/gltf_validate.h"
#include "support/bake_fixture.h"
#include "io/byte_stream.h"
#include "io/mesh_format.h"
#include "io/png_writer.h"
#include "output/export_job.h"
#include "output/export_mesh.h"
#include "output/lightmap.h"
#include "output/vertex_colors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>

namespace mebake::output {
namespace {

using nlohmann::json;
constexpr float kPi = float(std::numbers::pi);

solve::testing::MeshCollector ReadBack(const std::string& path, io::MeshFormat f) {
    solve::testing::MeshCollector m;
    auto in = io::InputStream::Open(path);
    io::ReadMesh(*in, f, m);
    return m;
}

std::vector<uint8_t> Slurp(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(f)),
                                std::istreambuf_iterator<char>());
}

class ExportTest : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = solve::testing::FreshDir("export");
        opt_.light[0] = {Vec3f(2, 4, 6), Vec3f(1, 1, 1)};
        opt_.light[1] = {Vec3f(1, 2, 3), Vec3f(0, 0, 0)};
        opt_.hole_fill_last = true;
        solve::testing::WriteTinyBake(dir_, opt_);
        // Each chart's own field: the charts disagree at x = 1 on purpose (stitching is
        // stitch_test's).
        view_ = OpenBakeView(dir_, FieldLoading::All, SeamStitching::Off);
        atlas_ = PackAtlas(ChartResolutions(view_), {});
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    std::string dir_;
    solve::testing::TinyBakeOptions opt_;
    BakeView view_;
    Atlas atlas_;
};

// The bake's path: the light map shaded once, written as EXR and PNG, and the PNG pages
// embedded in the .glb as they are: the same bytes as each written on its own.
TEST_F(ExportTest, LightMapPngBesideTheExrAndInTheGlbAreTheSameBytes) {
    const uint32_t pages = uint32_t(atlas_.pages.size());
    MapWriteOptions mo;
    mo.png_path = dir_ + "/both.png";
    const auto files = WriteMapPages(view_, atlas_, dir_ + "/both.exr", MapContent::Radiosity, mo);
    ASSERT_EQ(files.size(), 2u * pages);
    EXPECT_EQ(files.back(), PagePath(mo.png_path, pages - 1, pages));
    WriteMapPages(view_, atlas_, dir_ + "/alone.png", MapContent::Radiosity, MapWriteOptions{});
    WriteMapPages(view_, atlas_, dir_ + "/alone.exr", MapContent::Radiosity, MapWriteOptions{});
    for (uint32_t p = 0; p < pages; ++p) {
        const auto png = Slurp(PagePath(mo.png_path, p, pages));
        EXPECT_GT(png.size(), 8u);
        EXPECT_EQ(png, Slurp(PagePath(dir_ + "/alone.png", p, pages)));
        EXPECT_EQ(Slurp(PagePath(dir_ + "/both.exr", p, pages)),
                  Slurp(PagePath(dir_ + "/alone.exr", p, pages)));
    }
    MeshExportOptions encoded, embedded;
    for (uint32_t p = 0; p < pages; ++p)
        embedded.light_map_pngs.push_back(PagePath(mo.png_path, p, pages));
    WriteBakedMesh(view_, atlas_, dir_ + "/encoded.glb", encoded);
    WriteBakedMesh(view_, atlas_, dir_ + "/embedded.glb", embedded);
    EXPECT_EQ(Slurp(dir_ + "/encoded.glb"), Slurp(dir_ + "/embedded.glb"));
    // A PNG companion is for a radiosity EXR only.
    EXPECT_THROW(WriteMapPages(view_, atlas_, dir_ + "/x.png", MapContent::Radiosity, mo), Error);
    EXPECT_THROW(WriteMapPages(view_, atlas_, dir_ + "/e.exr", MapContent::Irradiance, mo), Error);
}

// `mebake export --lightmap x.exr --mesh y.glb` (no PNG asked for): the .glb embeds the PNG
// pages of the light map written from the EXR's texels into temporary files, which are gone
// afterwards; every output is the bytes of that output exported alone.
TEST_F(ExportTest, LightMapAndGlbTogetherAreTheBytesOfEachAlone) {
    const std::string tmp = dir_ + "/tmp";
    std::filesystem::create_directories(tmp);
    const char* old = std::getenv("TMPDIR");
    const std::string saved = old ? old : "";
    setenv("TMPDIR", tmp.c_str(), 1);
    ExportJobOptions both;
    both.dir = dir_;
    both.lightmap = dir_ + "/both.exr";
    both.mesh = dir_ + "/both.glb";
    both.stats = dir_ + "/both.json";
    RunExportJob(both);
    ExportJobOptions map = both, mesh = both;
    map.lightmap = dir_ + "/alone.exr";
    map.mesh = map.stats = "";
    mesh.lightmap = mesh.stats = "";
    mesh.mesh = dir_ + "/alone.glb";
    RunExportJob(map);
    RunExportJob(mesh);
    if (old)
        setenv("TMPDIR", saved.c_str(), 1);
    else
        unsetenv("TMPDIR");
    EXPECT_EQ(Slurp(dir_ + "/both.exr"), Slurp(dir_ + "/alone.exr"));
    EXPECT_EQ(Slurp(dir_ + "/both.glb"), Slurp(dir_ + "/alone.glb"));
    EXPECT_TRUE(std::filesystem::is_empty(tmp));
    std::ifstream in(dir_ + "/both.json");
    const json j = json::parse(in);
    EXPECT_EQ(j["lightmap"], json::array({dir_ + "/both.exr"}));
}

TEST_F(ExportTest, GlbWithEmbeddedLightMap) {
    const std::string path = dir_ + "/baked.glb";
    const MeshExportStats st = WriteBakedMesh(view_, atlas_, path, {});
    EXPECT_EQ(st.vertices, 8u);
    EXPECT_EQ(st.triangles, 4u);  // hole fills are part of the lit mesh
    const auto b = Slurp(path);
    ASSERT_GE(b.size(), 20u);
    uint32_t h[5];
    std::memcpy(h, b.data(), sizeof(h));
    EXPECT_EQ(h[0], 0x46546C67u);
    EXPECT_EQ(h[2], b.size());
    const json j = json::parse(b.begin() + 20, b.begin() + 20 + h[3]);
    const size_t bin = 20 + h[3] + 8;
    const auto& prims = j["meshes"][0]["primitives"];
    ASSERT_EQ(prims.size(), 1u);
    const json& apos = j["accessors"][prims[0]["attributes"]["POSITION"].get<size_t>()];
    EXPECT_EQ(apos["count"], 8);
    EXPECT_EQ(j["accessors"][prims[0]["indices"].get<size_t>()]["count"], 12);
    EXPECT_EQ(apos["min"], json({0.0, 0.0, 0.0}));
    EXPECT_EQ(apos["max"], json({2.0, 1.0, 0.0}));
    // uvs: the atlas uvs of each chart's vertices, charts in order.
    const json& auv = j["accessors"][prims[0]["attributes"]["TEXCOORD_1"].get<size_t>()];
    const json& vuv = j["bufferViews"][auv["bufferView"].get<size_t>()];
    std::vector<float> uv(16);
    std::memcpy(uv.data(),
                b.data() + bin + vuv["byteOffset"].get<size_t>() + auv.value("byteOffset", 0), 64);
    for (uint32_t c = 0; c < 2; ++c)
        for (int v = 0; v < 4; ++v) {
            const Vec2f want = atlas_.AtlasUv(c, Vec2f(float(v & 1), float(v >> 1)));
            EXPECT_EQ(uv[size_t(c * 8 + v * 2)], want.x);
            EXPECT_EQ(uv[size_t(c * 8 + v * 2 + 1)], want.y);
        }
    // The light map decodes at the page's size.
    const json& iv = j["bufferViews"][j["images"][0]["bufferView"].get<size_t>()];
    const io::PngImage png = io::DecodePng(
        std::span(b).subspan(bin + iv["byteOffset"].get<size_t>(), iv["byteLength"].get<size_t>()));
    EXPECT_EQ(uint32_t(png.width), atlas_.pages[0].width);
    EXPECT_EQ(uint32_t(png.height), atlas_.pages[0].height);
    if (auto v = mebake::testing::ValidateGltf(path)) {
        EXPECT_EQ(v->exit_code, 0) << v->report;
    } else {
        GTEST_SKIP() << "node or the gltf-validator package is not installed";
    }
}

TEST_F(ExportTest, PlyAndObjCarryBottomLeftUvs) {
    // PLY: per-vertex uvs read back.
    WriteBakedMesh(view_, atlas_, dir_ + "/m.ply", {});
    const auto m1 = ReadBack(dir_ + "/m.ply", io::MeshFormat::Ply);
    ASSERT_EQ(m1.position.size(), 8u);
    ASSERT_EQ(m1.uv.size(), 8u);
    ASSERT_EQ(m1.face_size.size(), 4u);
    EXPECT_EQ(m1.index[3], 0u);
    EXPECT_EQ(m1.index[6], 4u) << "chart 1's vertices follow chart 0's";
    // OBJ: the reader keeps vt records per corner, so read the text.
    WriteBakedMesh(view_, atlas_, dir_ + "/m.obj", {});
    std::vector<Vec2f> vt;
    {
        std::ifstream in(dir_ + "/m.obj");
        for (std::string line; std::getline(in, line);) {
            float s = 0, t = 0;
            if (std::sscanf(line.c_str(), "vt %f %f", &s, &t) == 2)
                vt.push_back(Vec2f(s, t));
        }
    }
    ASSERT_EQ(vt.size(), 8u);
    EXPECT_EQ(ReadBack(dir_ + "/m.obj", io::MeshFormat::Obj).position.size(), 8u);
    for (uint32_t c = 0; c < 2; ++c)
        for (uint32_t v = 0; v < 4; ++v) {
            const Vec2f a = atlas_.AtlasUv(c, Vec2f(float(v & 1), float(v >> 1)));
            for (const Vec2f& got : {m1.uv[c * 4 + v], vt[c * 4 + v]}) {
                EXPECT_FLOAT_EQ(got.x, a.x);
                EXPECT_FLOAT_EQ(got.y, 1 - a.y);
            }
        }
    // Several pages: UDIM tiles along u.
    AtlasOptions ao;
    ao.max_size = 16;
    const Atlas two = PackAtlas(ChartResolutions(view_), ao);
    ASSERT_EQ(two.pages.size(), 2u);
    WriteBakedMesh(view_, two, dir_ + "/two.ply", {});
    const auto m = ReadBack(dir_ + "/two.ply", io::MeshFormat::Ply);
    for (uint32_t c = 0; c < 2; ++c) {
        const float lo = float(two.charts[c].page);
        for (uint32_t v = 0; v < 4; ++v) {
            EXPECT_GE(m.uv[c * 4 + v].x, lo);
            EXPECT_LE(m.uv[c * 4 + v].x, lo + 1);
        }
    }
    // And a .glb with a material and a primitive per page.
    WriteBakedMesh(view_, two, dir_ + "/two.glb", {});
    const auto b = Slurp(dir_ + "/two.glb");
    uint32_t jl;
    std::memcpy(&jl, b.data() + 12, 4);
    const json j = json::parse(b.begin() + 20, b.begin() + 20 + jl);
    EXPECT_EQ(j["materials"].size(), 2u);
    EXPECT_EQ(j["meshes"][0]["primitives"].size(), 2u);
    EXPECT_THROW(WriteBakedMesh(view_, atlas_, dir_ + "/m.stl", {}), Error);
}

TEST_F(ExportTest, VertexColorsInInputOrder) {
    const std::string path = dir_ + "/vc.ply";
    const VertexColorStats st = WriteVertexColors(view_, path, {});
    EXPECT_EQ(st.vertices, 7u);
    EXPECT_EQ(st.referenced, 6u);
    EXPECT_EQ(st.shared, 2u);  // vertices 1 and 4
    EXPECT_EQ(st.faces, 3u);
    EXPECT_EQ(st.hole_fill_faces, 1u);
    const auto m = ReadBack(path, io::MeshFormat::Ply);
    ASSERT_EQ(m.position.size(), 7u);
    ASSERT_EQ(m.color.size(), 7u);
    // Per vertex: the charts using it and the u it has there.
    const std::vector<std::vector<std::pair<int, double>>> uses = {
        {{0, 0}}, {{0, 1}, {1, 0}}, {{1, 1}}, {{0, 0}}, {{0, 1}, {1, 0}}, {{1, 1}}, {}};
    for (uint64_t id = 0; id < 7; ++id) {
        EXPECT_EQ(m.position[id], solve::testing::GlobalVertex(id));
        Vec3f b{};
        for (auto [c, u] : uses[id])
            b += solve::testing::ExpectedB(opt_, c, u);
        if (!uses[id].empty())
            b = b / float(uses[id].size());
        uint8_t want[3];
        ToneMapPixel(b / kPi, {}, want);
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(std::lround(m.color[id][k] * 255), want[k], 1) << "vertex " << id;
    }
    EXPECT_EQ(m.color[6], Vec3f(0, 0, 0));
    // Faces as global ids, tile by tile; the hole fill is gone.
    ASSERT_EQ(m.index.size(), 9u);
    EXPECT_EQ(std::vector<uint64_t>(m.index.begin(), m.index.begin() + 6),
              (std::vector<uint64_t>{0, 1, 4, 0, 4, 3}));
    EXPECT_EQ(std::vector<uint64_t>(m.index.begin() + 6, m.index.end()),
              (std::vector<uint64_t>{1, 2, 5}));

    // Linear float colours on request.
    VertexColorOptions vo;
    vo.float_colors = true;
    vo.tone.exposure = -2;  // PLY readers clamp float colours to [0, 1]
    WriteVertexColors(view_, dir_ + "/vcf.ply", vo);
    const auto f = ReadBack(dir_ + "/vcf.ply", io::MeshFormat::Ply);
    EXPECT_TRUE(f.header.colors_are_float);
    const Vec3f b0 = solve::testing::ExpectedB(opt_, 0, 0) / kPi * 0.25f;
    for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(f.color[0][k], b0[k], 1e-5);
}

TEST_F(ExportTest, MissingVertexSpillIsAnError) {
    std::filesystem::remove(stream::Spill::VerticesPath(dir_));
    EXPECT_THROW(WriteVertexColors(view_, dir_ + "/vc.ply", {}), Error);
    EXPECT_FALSE(std::filesystem::exists(dir_ + "/vc.ply"));
}

}  // namespace
}  // namespace mebake::output
