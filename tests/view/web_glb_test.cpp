// The viewer's .glb chunks (view/web_glb.h): the container's layout, the accessors, and
// EXT_meshopt_compression buffers that decode (meshoptimizer's own decoder) to exactly the
// bytes of the plain file.
#include "view/web_glb.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <meshoptimizer.h>
#include <nlohmann/json.hpp>

namespace mebake::view {
namespace {

struct Parsed {
    nlohmann::json json;
    std::vector<uint8_t> bin;
};

uint32_t U32(const std::vector<uint8_t>& b, size_t at) {
    uint32_t v;
    std::memcpy(&v, &b[at], 4);
    return v;
}

Parsed Parse(const std::vector<uint8_t>& glb) {
    Parsed p;
    EXPECT_EQ(U32(glb, 0), 0x46546C67u);
    EXPECT_EQ(U32(glb, 4), 2u);
    EXPECT_EQ(U32(glb, 8), glb.size());
    const uint32_t jlen = U32(glb, 12);
    EXPECT_EQ(jlen % 4, 0u);
    p.json = nlohmann::json::parse(glb.begin() + 20, glb.begin() + 20 + jlen);
    const uint32_t blen = U32(glb, 20 + jlen);
    EXPECT_EQ(U32(glb, 24 + jlen), 0x004E4942u);
    p.bin.assign(glb.begin() + 28 + jlen, glb.begin() + 28 + jlen + blen);
    return p;
}

// A 3x3 grid of vertices (8 triangles) and its outline as lines.
WebGlb Grid(bool meshopt) {
    WebGlb g(meshopt);
    GlbPrimitive p;
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
            p.position.push_back(Vec3f(float(i), float(j), 0.1f * float(i * j)));
            p.normal.push_back(Vec3f(0, 0, 1));
            p.atlas_uv.push_back(Vec2f(0.25f * float(i), 0.25f * float(j)));
            p.chart_uv.push_back(Vec2f(0.5f * float(i), 0.5f * float(j)));
            p.color.push_back({0.5f, 0.25f, float(i) / 2, 1});
        }
    for (uint32_t j = 0; j < 2; ++j)
        for (uint32_t i = 0; i < 2; ++i) {
            const uint32_t a = j * 3 + i;
            p.indices.insert(p.indices.end(), {a, a + 1, a + 4, a, a + 4, a + 3});
        }
    p.material = g.AddMaterial("m", {{"glossy_exponent", 20}});
    GlbPrimitive lines = p;
    lines.lines = true;
    lines.indices = {0, 1, 1, 2, 2, 5, 5, 8};
    lines.material = g.AddMaterial("borders", {{"borders", true}});
    g.AddPrimitive(p);
    g.AddPrimitive(lines);
    return g;
}

TEST(WebGlb, PlainLayout) {
    const Parsed p = Parse(Grid(false).Finish());
    const auto& prim = p.json["meshes"][0]["primitives"];
    ASSERT_EQ(prim.size(), 2u);
    EXPECT_EQ(prim[0]["mode"], 4);
    EXPECT_EQ(prim[1]["mode"], 1);
    const auto& attr = prim[0]["attributes"];
    for (const char* a : {"POSITION", "NORMAL", "TEXCOORD_0", "TEXCOORD_1", "COLOR_0"})
        EXPECT_TRUE(attr.contains(a)) << a;
    const auto& pos = p.json["accessors"][attr["POSITION"].get<int>()];
    EXPECT_EQ(pos["count"], 9);
    EXPECT_EQ(pos["max"][2].get<float>(), 0.4f);
    EXPECT_EQ(p.json["materials"][0]["extras"]["glossy_exponent"], 20);
    EXPECT_FALSE(p.json.contains("extensionsUsed"));
    // The index view holds the indices as given.
    const auto& ind = p.json["accessors"][prim[0]["indices"].get<int>()];
    const auto& view = p.json["bufferViews"][ind["bufferView"].get<int>()];
    uint32_t first[6];
    std::memcpy(first, &p.bin[view["byteOffset"].get<size_t>()], sizeof first);
    EXPECT_EQ(first[2], 4u);
    EXPECT_EQ(first[5], 3u);
}

// Every buffer view decoded (meshopt's own decoder) into its place in a fallback buffer.
std::vector<uint8_t> Decode(const Parsed& enc) {
    std::vector<uint8_t> fallback(enc.json["buffers"][1]["byteLength"].get<size_t>());
    for (const auto& view : enc.json["bufferViews"]) {
        const auto& ext = view["extensions"]["EXT_meshopt_compression"];
        const size_t count = ext["count"], stride = ext["byteStride"];
        const size_t off = ext["byteOffset"], len = ext["byteLength"];
        uint8_t* out = &fallback[view["byteOffset"].get<size_t>()];
        const std::string mode = ext["mode"];
        int r;
        if (mode == "ATTRIBUTES")
            r = meshopt_decodeVertexBuffer(out, count, stride, &enc.bin[off], len);
        else if (mode == "TRIANGLES")
            r = meshopt_decodeIndexBuffer(out, count, stride, &enc.bin[off], len);
        else
            r = meshopt_decodeIndexSequence(out, count, stride, &enc.bin[off], len);
        EXPECT_EQ(r, 0) << mode;
    }
    return fallback;
}

// Primitive p's triangles (or segments) as position tuples, each rotated to start at its
// smallest vertex, sorted: the mesh whatever the order of its triangles and vertices.
std::vector<std::vector<float>> Shapes(const nlohmann::json& j, const std::vector<uint8_t>& buf,
                                       int p) {
    const auto& prim = j["meshes"][0]["primitives"][p];
    const int k = prim["mode"] == 4 ? 3 : 2;
    auto data = [&](int accessor) {
        const auto& a = j["accessors"][accessor];
        return &buf[j["bufferViews"][a["bufferView"].get<int>()]["byteOffset"].get<size_t>()];
    };
    const auto* ind = reinterpret_cast<const uint32_t*>(data(prim["indices"]));
    const auto* pos = reinterpret_cast<const float*>(data(prim["attributes"]["POSITION"]));
    const size_t n = j["accessors"][prim["indices"].get<int>()]["count"];
    std::vector<std::vector<float>> out;
    for (size_t t = 0; t < n; t += size_t(k)) {
        std::vector<std::vector<float>> v;
        for (int c = 0; c < k; ++c)
            v.push_back({pos[3 * ind[t + c]], pos[3 * ind[t + c] + 1], pos[3 * ind[t + c] + 2]});
        std::rotate(v.begin(), std::min_element(v.begin(), v.end()), v.end());
        std::vector<float> flat;
        for (const auto& x : v)
            flat.insert(flat.end(), x.begin(), x.end());
        out.push_back(flat);
    }
    std::sort(out.begin(), out.end());
    return out;
}

TEST(WebGlb, MeshoptDecodesToTheSameMesh) {
    const Parsed plain = Parse(Grid(false).Finish());
    const Parsed enc = Parse(Grid(true).Finish());
    EXPECT_EQ(enc.json["extensionsRequired"][0], "EXT_meshopt_compression");
    EXPECT_TRUE(enc.json["buffers"][1]["extensions"]["EXT_meshopt_compression"]["fallback"]);
    const std::vector<uint8_t> decoded = Decode(enc);
    for (int p = 0; p < 2; ++p) {
        const auto a = Shapes(plain.json, plain.bin, p), b = Shapes(enc.json, decoded, p);
        EXPECT_EQ(a.size(), p == 0 ? 8u : 4u);
        EXPECT_EQ(a, b) << "primitive " << p;
    }
}

}  // namespace
}  // namespace mebake::view
