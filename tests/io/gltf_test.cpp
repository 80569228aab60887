// .glb writer: container layout (magic, chunk lengths and alignment), JSON contents
// (accessor counts, POSITION min/max, materials in both light-map modes), binary data read
// back through the accessors, and the Khronos validator when it is installed.
#include "core/error.h"
#include "support/gltf_validate.h"
#include "io/gltf_writer.h"
#include "io/png_writer.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <unistd.h>

namespace mebake::io {
namespace {

using nlohmann::json;

uint32_t U32(const std::vector<uint8_t>& b, size_t at) {
    uint32_t v;
    std::memcpy(&v, b.data() + at, 4);
    return v;
}

struct Glb {
    json j;
    std::vector<uint8_t> bin;
};

Glb Parse(const std::vector<uint8_t>& b) {
    Glb g;
    EXPECT_GE(b.size(), 20u);
    EXPECT_EQ(U32(b, 0), 0x46546C67u) << "magic glTF";
    EXPECT_EQ(U32(b, 4), 2u);
    EXPECT_EQ(U32(b, 8), b.size());
    const uint32_t jlen = U32(b, 12);
    EXPECT_EQ(U32(b, 16), 0x4E4F534Au) << "JSON chunk";
    EXPECT_EQ(jlen % 4, 0u);
    g.j = json::parse(b.begin() + 20, b.begin() + 20 + jlen);
    const size_t at = 20 + jlen;
    if (at < b.size()) {
        const uint32_t blen = U32(b, at);
        EXPECT_EQ(U32(b, at + 4), 0x004E4942u) << "BIN chunk";
        EXPECT_EQ(blen % 4, 0u);
        EXPECT_EQ(at + 8 + blen, b.size());
        g.bin.assign(b.begin() + long(at) + 8, b.end());
    }
    return g;
}

template <typename T>
std::vector<T> ReadAccessor(const Glb& g, size_t a, int components) {
    const json& acc = g.j["accessors"][a];
    const json& view = g.j["bufferViews"][acc["bufferView"].get<size_t>()];
    const size_t off = view["byteOffset"].get<size_t>() + acc.value("byteOffset", size_t(0));
    const size_t n = acc["count"].get<size_t>() * size_t(components);
    EXPECT_LE(off + n * sizeof(T),
              view["byteOffset"].get<size_t>() + view["byteLength"].get<size_t>());
    std::vector<T> out(n);
    std::memcpy(out.data(), g.bin.data() + off, n * sizeof(T));
    return out;
}

std::vector<uint8_t> TinyPng() {
    const uint8_t px[2 * 2 * 3] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 128, 128, 128};
    return EncodePng(2, 2, 3, px);
}

std::vector<uint8_t> WriteSample(GlbLightMapMode mode) {
    GlbOptions opt;
    opt.mode = mode;
    GlbWriter w(opt);
    const auto png = TinyPng();
    EXPECT_EQ(w.AddLightMapMaterial(png, "page 1"), 0u);
    w.BeginPrimitive(0);
    const std::vector<Vec3f> pos{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, -2}};
    const std::vector<Vec3f> nrm{{0, 0, 2}, {0, 0, 1}, {0, 0, 0}, {0, 0, 1}};
    const std::vector<Vec2f> uv{{0, 0}, {0.5f, 0}, {0, 0.5f}, {0.5f, 0.5f}};
    EXPECT_EQ(w.AddVertices(pos, nrm, uv), 0u);
    const std::vector<std::array<uint32_t, 3>> tris{{0, 1, 3}, {0, 3, 2}};
    w.AddTriangles(tris);
    w.BeginPrimitive(0);
    const std::vector<Vec3f> pos2{{5, 5, 5}, {6, 5, 5}, {5, 6, 5}};
    const std::vector<Vec3f> nrm2{{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    const std::vector<Vec2f> uv2{{0.6f, 0.6f}, {0.9f, 0.6f}, {0.6f, 0.9f}};
    EXPECT_EQ(w.AddVertices(pos2, nrm2, uv2), 0u);
    const std::vector<std::array<uint32_t, 3>> tri2{{0, 1, 2}};
    w.AddTriangles(tri2);
    std::vector<uint8_t> bytes;
    auto out = OutputStream::ToMemory(&bytes);
    w.Finish(*out);
    return bytes;
}

TEST(Glb, LayoutAndAccessors) {
    const auto bytes = WriteSample(GlbLightMapMode::Emissive);
    const Glb g = Parse(bytes);
    const json& j = g.j;
    EXPECT_EQ(j["asset"]["version"], "2.0");
    for (const auto& v : j["bufferViews"])
        EXPECT_EQ(v["byteOffset"].get<size_t>() % 4, 0u);
    const auto& prims = j["meshes"][0]["primitives"];
    ASSERT_EQ(prims.size(), 2u);
    const size_t a_pos = prims[0]["attributes"]["POSITION"], a_idx = prims[0]["indices"];
    EXPECT_EQ(j["accessors"][a_pos]["count"], 4);
    EXPECT_EQ(j["accessors"][a_idx]["count"], 6);
    EXPECT_EQ(j["accessors"][a_idx]["componentType"], 5125);
    EXPECT_EQ(j["accessors"][a_pos]["min"], json({0.0, 0.0, -2.0}));
    EXPECT_EQ(j["accessors"][a_pos]["max"], json({1.0, 1.0, 0.0}));
    EXPECT_EQ(prims[0]["attributes"]["TEXCOORD_0"], prims[0]["attributes"]["TEXCOORD_1"]);
    const auto pos = ReadAccessor<float>(g, a_pos, 3);
    EXPECT_EQ(pos[9], 1.f);
    EXPECT_EQ(pos[11], -2.f);
    const auto nrm = ReadAccessor<float>(g, prims[0]["attributes"]["NORMAL"], 3);
    EXPECT_EQ(nrm[2], 1.f) << "normalized";
    EXPECT_EQ(nrm[8], 1.f) << "a zero normal becomes +Z";
    const auto idx = ReadAccessor<uint32_t>(g, a_idx, 1);
    EXPECT_EQ(idx, (std::vector<uint32_t>{0, 1, 3, 0, 3, 2}));
    // The second primitive's indices are its own.
    const auto idx2 = ReadAccessor<uint32_t>(g, prims[1]["indices"], 1);
    EXPECT_EQ(idx2, (std::vector<uint32_t>{0, 1, 2}));
    const auto pos2 = ReadAccessor<float>(g, prims[1]["attributes"]["POSITION"], 3);
    EXPECT_EQ(pos2[0], 5.f);
    // The material shows the light map as emission on TEXCOORD_1, over a black base.
    const json& m = j["materials"][0];
    EXPECT_EQ(m["emissiveTexture"]["texCoord"], 1);
    EXPECT_EQ(m["emissiveFactor"], json({1.0, 1.0, 1.0}));
    EXPECT_EQ(m["pbrMetallicRoughness"]["baseColorFactor"], json({0.0, 0.0, 0.0, 1.0}));
    // The embedded image is the PNG, byte for byte.
    const json& iv = j["bufferViews"][j["images"][0]["bufferView"].get<size_t>()];
    const auto png = TinyPng();
    ASSERT_EQ(iv["byteLength"].get<size_t>(), png.size());
    EXPECT_EQ(0,
              std::memcmp(g.bin.data() + iv["byteOffset"].get<size_t>(), png.data(), png.size()));
    EXPECT_EQ(DecodePng(png).width, 2);
}

TEST(Glb, UnlitMode) {
    const Glb g = Parse(WriteSample(GlbLightMapMode::Unlit));
    EXPECT_EQ(g.j["extensionsUsed"], json({"KHR_materials_unlit"}));
    const json& m = g.j["materials"][0];
    EXPECT_TRUE(m["extensions"].contains("KHR_materials_unlit"));
    EXPECT_EQ(m["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"], 1);
}

TEST(Glb, EmptyMeshIsStillAFile) {
    GlbWriter w;
    std::vector<uint8_t> bytes;
    auto out = OutputStream::ToMemory(&bytes);
    w.Finish(*out);
    const Glb g = Parse(bytes);
    EXPECT_FALSE(g.j.contains("meshes"));
    EXPECT_TRUE(g.bin.empty());
}

TEST(Glb, PassesTheKhronosValidator) {
    const auto dir =
        std::filesystem::temp_directory_path() / ("mebake-gltf-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    bool ran = false;
    for (auto mode : {GlbLightMapMode::Emissive, GlbLightMapMode::Unlit}) {
        const std::string file = (dir / "sample.glb").string();
        auto out = OutputStream::Open(file);
        const auto bytes = WriteSample(mode);
        out->Write(bytes.data(), bytes.size());
        out->Commit();
        auto v = testing::ValidateGltf(file);
        if (!v)
            break;
        ran = true;
        EXPECT_EQ(v->exit_code, 0) << v->report;
        EXPECT_NE(v->report.find("\"numErrors\": 0"), std::string::npos) << v->report;
    }
    std::filesystem::remove_all(dir);
    if (!ran)
        GTEST_SKIP() << "node or the gltf-validator package is not installed";
}

}  // namespace
}  // namespace mebake::io
