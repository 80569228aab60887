// glTF 2.0 .glb writer: vertex attributes stream to four anonymous spill files (one per
// attribute kind, so each becomes one contiguous buffer view); Finish() writes the JSON
// chunk, then the binary chunk = [PNGs][positions][normals][uvs][indices], each part
// padded to 4 bytes. Primitives are accessor windows (byteOffset) into those views.
#include "io/gltf_writer.h"
#include "io/spill_file.h"

#include "core/check.h"
#include "core/error.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

namespace mebake::io {

namespace {

constexpr uint32_t kGlbMagic = 0x46546C67;   // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr uint32_t kChunkBin = 0x004E4942;   // "BIN\0"
constexpr uint32_t kFloat = 5126, kUnsignedInt = 5125;
constexpr uint32_t kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr uint32_t kLinear = 9729, kClampToEdge = 33071;
// Index 2^32 - 1 is the primitive-restart value glTF forbids.
constexpr uint64_t kMaxPrimitiveVertices = 0xFFFFFFFEull;

uint64_t Pad4(uint64_t n) {
    return (n + 3) & ~uint64_t(3);
}

void WriteU32(OutputStream& out, uint32_t v) {
    uint8_t b[4] = {uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16), uint8_t(v >> 24)};
    out.Write(b, 4);
}

void WritePadding(OutputStream& out, uint64_t n, uint8_t byte) {
    const uint8_t pad[3] = {byte, byte, byte};
    out.Write(pad, size_t(Pad4(n) - n));
}

}  // namespace

struct GlbWriter::Impl {
    struct Primitive {
        uint32_t material = 0;
        uint64_t first_vertex = 0, vertices = 0;  // in the attribute spills
        uint64_t first_index = 0, indices = 0;    // in the index spill
        Vec3f min{INFINITY, INFINITY, INFINITY}, max{-INFINITY, -INFINITY, -INFINITY};
    };
    struct Material {
        std::string name;
        std::vector<uint8_t> png;
    };
    GlbOptions options;
    std::unique_ptr<SpillFile> positions, normals, uvs, indices;
    std::vector<Material> materials;
    std::vector<Primitive> primitives;
    uint64_t vertices = 0, index_count = 0;
    std::vector<float> scratch;
    std::vector<uint32_t> index_scratch;
};

GlbWriter::GlbWriter(const GlbOptions& options) : impl_(std::make_unique<Impl>()) {
    impl_->options = options;
    const std::string& dir = options.temp_dir;
    impl_->positions = std::make_unique<SpillFile>(dir, "glTF writer");
    impl_->normals = std::make_unique<SpillFile>(dir, "glTF writer");
    impl_->uvs = std::make_unique<SpillFile>(dir, "glTF writer");
    impl_->indices = std::make_unique<SpillFile>(dir, "glTF writer");
}

GlbWriter::~GlbWriter() = default;

uint32_t GlbWriter::AddLightMapMaterial(std::vector<uint8_t> png, const std::string& name) {
    CHECK(!png.empty());
    impl_->materials.push_back({name, std::move(png)});
    return uint32_t(impl_->materials.size() - 1);
}

void GlbWriter::BeginPrimitive(uint32_t material) {
    CHECK_LT(material, impl_->materials.size());
    Impl::Primitive p;
    p.material = material;
    p.first_vertex = impl_->vertices;
    p.first_index = impl_->index_count;
    impl_->primitives.push_back(p);
}

uint64_t GlbWriter::primitive_vertices() const {
    return impl_->primitives.empty() ? 0 : impl_->primitives.back().vertices;
}

uint32_t GlbWriter::AddVertices(std::span<const Vec3f> position, std::span<const Vec3f> normal,
                                std::span<const Vec2f> uv) {
    Impl& m = *impl_;
    CHECK(!m.primitives.empty());
    CHECK_EQ(position.size(), normal.size());
    CHECK_EQ(position.size(), uv.size());
    Impl::Primitive& p = m.primitives.back();
    CHECK_LE(p.vertices + position.size(), kMaxPrimitiveVertices);
    const uint32_t first = uint32_t(p.vertices);
    for (const Vec3f& q : position) {
        CHECK(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z));
        p.min = Min(p.min, q);
        p.max = Max(p.max, q);
    }
    m.positions->Write(position.data(), position.size_bytes());
    m.scratch.clear();
    for (const Vec3f& n : normal) {
        Vec3d d = Normalize(Vec3d(n));
        Vec3f u = Dot(d, d) > 0 && std::isfinite(d.x + d.y + d.z) ? Vec3f(d) : Vec3f(0, 0, 1);
        m.scratch.insert(m.scratch.end(), {u.x, u.y, u.z});
    }
    m.normals->Write(m.scratch.data(), m.scratch.size() * sizeof(float));
    for (const Vec2f& t : uv)
        CHECK(std::isfinite(t.x) && std::isfinite(t.y));
    m.uvs->Write(uv.data(), uv.size_bytes());
    p.vertices += position.size();
    m.vertices += position.size();
    return first;
}

void GlbWriter::AddTriangles(std::span<const std::array<uint32_t, 3>> triangles) {
    Impl& m = *impl_;
    CHECK(!m.primitives.empty());
    Impl::Primitive& p = m.primitives.back();
    m.index_scratch.clear();
    for (const auto& t : triangles)
        for (uint32_t v : t) {
            CHECK_LT(uint64_t(v), p.vertices);
            m.index_scratch.push_back(v);
        }
    m.indices->Write(m.index_scratch.data(), m.index_scratch.size() * sizeof(uint32_t));
    p.indices += m.index_scratch.size();
    m.index_count += m.index_scratch.size();
}

void GlbWriter::Finish(OutputStream& out) {
    using nlohmann::json;
    Impl& m = *impl_;
    json j;
    j["asset"] = {{"version", "2.0"}, {"generator", m.options.generator}};
    const bool unlit = m.options.mode == GlbLightMapMode::Unlit;
    if (unlit)
        j["extensionsUsed"] = {"KHR_materials_unlit"};

    // Binary chunk layout.
    json views = json::array(), accessors = json::array(), images = json::array();
    uint64_t offset = 0;
    for (const auto& mat : m.materials) {
        images.push_back({{"bufferView", views.size()}, {"mimeType", "image/png"}});
        views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", mat.png.size()}});
        offset = Pad4(offset + mat.png.size());
    }
    // Several primitives' accessors share a vertex view, which glTF allows only with an
    // explicit byteStride (index views must not have one).
    auto add_view = [&](uint64_t bytes, uint32_t target, uint32_t stride) -> int64_t {
        if (bytes == 0)
            return -1;
        json v = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}, {"target", target}};
        if (stride)
            v["byteStride"] = stride;
        views.push_back(v);
        offset = Pad4(offset + bytes);
        return int64_t(views.size() - 1);
    };
    const int64_t v_pos = add_view(m.positions->size(), kArrayBuffer, 12);
    const int64_t v_nrm = add_view(m.normals->size(), kArrayBuffer, 12);
    const int64_t v_uv = add_view(m.uvs->size(), kArrayBuffer, 8);
    const int64_t v_idx = add_view(m.indices->size(), kElementArrayBuffer, 0);
    const uint64_t bin_bytes = offset;

    json prims = json::array();
    for (const auto& p : m.primitives) {
        if (p.indices == 0 || p.vertices == 0)
            continue;  // glTF accessors need count >= 1
        auto accessor = [&](int64_t view, uint64_t byte_offset, uint32_t component, uint64_t count,
                            const char* type) {
            accessors.push_back({{"bufferView", view},
                                 {"byteOffset", byte_offset},
                                 {"componentType", component},
                                 {"count", count},
                                 {"type", type}});
            return accessors.size() - 1;
        };
        const size_t a_pos = accessor(v_pos, p.first_vertex * 12, kFloat, p.vertices, "VEC3");
        accessors[a_pos]["min"] = {p.min.x, p.min.y, p.min.z};
        accessors[a_pos]["max"] = {p.max.x, p.max.y, p.max.z};
        const size_t a_nrm = accessor(v_nrm, p.first_vertex * 12, kFloat, p.vertices, "VEC3");
        const size_t a_uv = accessor(v_uv, p.first_vertex * 8, kFloat, p.vertices, "VEC2");
        const size_t a_idx = accessor(v_idx, p.first_index * 4, kUnsignedInt, p.indices, "SCALAR");
        prims.push_back(
            {{"attributes",
              {{"POSITION", a_pos}, {"NORMAL", a_nrm}, {"TEXCOORD_0", a_uv}, {"TEXCOORD_1", a_uv}}},
             {"indices", a_idx},
             {"material", p.material},
             {"mode", 4}});
    }
    if (prims.empty()) {
        j["scenes"] = json::array({json::object()});
    } else {
        j["scenes"] = json::array({{{"nodes", {0}}}});
        j["nodes"] = json::array({{{"mesh", 0}, {"name", "baked"}}});
        j["meshes"] = json::array({{{"primitives", prims}, {"name", "baked"}}});
    }
    j["scene"] = 0;
    if (!m.materials.empty()) {
        json mats = json::array(), textures = json::array();
        for (size_t k = 0; k < m.materials.size(); ++k) {
            textures.push_back({{"sampler", 0}, {"source", k}});
            json mat = {{"name", m.materials[k].name}};
            const json tex = {{"index", k}, {"texCoord", 1}};
            if (unlit) {
                mat["pbrMetallicRoughness"] = {
                    {"baseColorTexture", tex}, {"metallicFactor", 0.0}, {"roughnessFactor", 1.0}};
                mat["extensions"] = {{"KHR_materials_unlit", json::object()}};
            } else {
                mat["pbrMetallicRoughness"] = {{"baseColorFactor", {0.0, 0.0, 0.0, 1.0}},
                                               {"metallicFactor", 0.0},
                                               {"roughnessFactor", 1.0}};
                mat["emissiveTexture"] = tex;
                mat["emissiveFactor"] = {1.0, 1.0, 1.0};
            }
            mats.push_back(mat);
        }
        j["materials"] = mats;
        j["textures"] = textures;
        j["images"] = images;
        j["samplers"] = json::array({{{"magFilter", kLinear},
                                      {"minFilter", kLinear},
                                      {"wrapS", kClampToEdge},
                                      {"wrapT", kClampToEdge}}});
    }
    if (bin_bytes > 0) {
        j["buffers"] = json::array({{{"byteLength", bin_bytes}}});
        j["bufferViews"] = views;
    }
    if (!accessors.empty())
        j["accessors"] = accessors;

    const std::string text = j.dump();
    const uint64_t json_bytes = Pad4(text.size());
    const uint64_t total = 12 + 8 + json_bytes + (bin_bytes > 0 ? 8 + bin_bytes : 0);
    if (total > 0xFFFFFFFFull)
        InputError({out.name()},
                   "the mesh needs {} bytes but a .glb holds at most 4 GiB; export PLY or OBJ",
                   total);
    const uint64_t start = out.offset();
    WriteU32(out, kGlbMagic);
    WriteU32(out, 2);
    WriteU32(out, uint32_t(total));
    WriteU32(out, uint32_t(json_bytes));
    WriteU32(out, kChunkJson);
    out.Write(text);
    WritePadding(out, text.size(), ' ');
    if (bin_bytes > 0) {
        WriteU32(out, uint32_t(bin_bytes));
        WriteU32(out, kChunkBin);
        for (const auto& mat : m.materials) {
            out.Write(mat.png.data(), mat.png.size());
            WritePadding(out, mat.png.size(), 0);
        }
        for (SpillFile* s : {m.positions.get(), m.normals.get(), m.uvs.get(), m.indices.get()}) {
            s->CopyTo(out);
            WritePadding(out, s->size(), 0);
        }
    }
    CHECK_EQ(out.offset() - start, total);
    out.Commit();
}

}  // namespace mebake::io
