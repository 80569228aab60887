#include "view/web_glb.h"

#include "core/check.h"

#include <cstring>
#include <meshoptimizer.h>

namespace mebake::view {

namespace {

constexpr uint32_t kFloat = 5126, kUint32 = 5125;

template <typename T>
std::span<const uint8_t> Bytes(const std::vector<T>& v) {
    return {reinterpret_cast<const uint8_t*>(v.data()), v.size() * sizeof(T)};
}

void Pad4(std::vector<uint8_t>& b, uint8_t fill) {
    while (b.size() % 4)
        b.push_back(fill);
}

void Append32(std::vector<uint8_t>& b, uint32_t v) {
    for (int k = 0; k < 4; ++k)
        b.push_back(uint8_t(v >> (8 * k)));
}

template <typename T>
void Remap(std::vector<T>& v, const std::vector<uint32_t>& remap, size_t unique) {
    if (v.empty())
        return;
    std::vector<T> out(unique);
    meshopt_remapVertexBuffer(out.data(), v.data(), v.size(), sizeof(T), remap.data());
    v = std::move(out);
}

// Triangles in vertex-cache order and vertices in first-use order (meshoptimizer): the
// same mesh, but the index deltas and neighbouring vertices the encoder sees are small.
void OptimizeOrder(GlbPrimitive& p) {
    const size_t n = p.position.size();
    meshopt_optimizeVertexCache(p.indices.data(), p.indices.data(), p.indices.size(), n);
    std::vector<uint32_t> remap(n);
    const size_t unique =
        meshopt_optimizeVertexFetchRemap(remap.data(), p.indices.data(), p.indices.size(), n);
    meshopt_remapIndexBuffer(p.indices.data(), p.indices.data(), p.indices.size(), remap.data());
    Remap(p.position, remap, unique);
    Remap(p.normal, remap, unique);
    Remap(p.atlas_uv, remap, unique);
    Remap(p.chart_uv, remap, unique);
    Remap(p.color, remap, unique);
}

}  // namespace

uint32_t WebGlb::AddMaterial(const std::string& name, nlohmann::json extras) {
    materials_.push_back(
        {{"name", name},
         {"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1, 1}}, {"metallicFactor", 0}}},
         {"doubleSided", true},
         {"extras", std::move(extras)}});
    return uint32_t(materials_.size() - 1);
}

uint32_t WebGlb::View(std::span<const uint8_t> bytes, size_t count, size_t stride, bool indices,
                      bool vertex_data) {
    raw_bytes_ += bytes.size();
    // With meshopt, buffer 0 (the GLB's binary chunk) holds the encoded data and buffer 1
    // is the fallback the views decode into; without, the views are in buffer 0.
    nlohmann::json v = {{"buffer", meshopt_ ? 1 : 0}, {"byteLength", bytes.size()}};
    if (vertex_data)
        v["byteStride"] = stride;
    if (!meshopt_) {
        v["byteOffset"] = bin_.size();
        bin_.insert(bin_.end(), bytes.begin(), bytes.end());
        Pad4(bin_, 0);
    } else {
        std::vector<uint8_t> enc;
        const char* mode = "ATTRIBUTES";
        const auto* idx = reinterpret_cast<const uint32_t*>(bytes.data());
        size_t max_index = 0;
        for (size_t i = 0; indices && i < count; ++i)
            max_index = std::max<size_t>(max_index, idx[i]);
        if (indices && count % 3 == 0 && !vertex_data) {
            mode = "TRIANGLES";
            enc.resize(meshopt_encodeIndexBufferBound(count, max_index + 1));
            enc.resize(meshopt_encodeIndexBuffer(enc.data(), enc.size(), idx, count));
        } else if (indices) {
            mode = "INDICES";
            enc.resize(meshopt_encodeIndexSequenceBound(count, max_index + 1));
            enc.resize(meshopt_encodeIndexSequence(enc.data(), enc.size(), idx, count));
        } else {
            enc.resize(meshopt_encodeVertexBufferBound(count, stride));
            enc.resize(
                meshopt_encodeVertexBuffer(enc.data(), enc.size(), bytes.data(), count, stride));
        }
        CHECK(!enc.empty());
        v["extensions"]["EXT_meshopt_compression"] = {{"buffer", 0},
                                                      {"byteOffset", bin_.size()},
                                                      {"byteLength", enc.size()},
                                                      {"byteStride", stride},
                                                      {"count", count},
                                                      {"mode", mode}};
        v["byteOffset"] = raw_bytes_ - bytes.size();  // into the fallback buffer
        bin_.insert(bin_.end(), enc.begin(), enc.end());
        Pad4(bin_, 0);
    }
    views_.push_back(std::move(v));
    return uint32_t(views_.size() - 1);
}

uint32_t WebGlb::Accessor(uint32_t view, uint32_t component, size_t count, const char* type,
                          nlohmann::json extra) {
    nlohmann::json a = {
        {"bufferView", view}, {"componentType", component}, {"count", count}, {"type", type}};
    if (extra.is_object())
        a.update(extra);
    accessors_.push_back(std::move(a));
    return uint32_t(accessors_.size() - 1);
}

void WebGlb::AddPrimitive(GlbPrimitive p) {
    const size_t n = p.position.size();
    if (n == 0 || p.indices.empty())
        return;
    CHECK(p.normal.size() == n && p.atlas_uv.size() == n && p.chart_uv.size() == n);
    CHECK(p.color.empty() || p.color.size() == n);
    CHECK_EQ(p.indices.size() % (p.lines ? 2 : 3), 0u);
    if (meshopt_ && !p.lines)
        OptimizeOrder(p);
    Vec3f lo = p.position[0], hi = p.position[0];
    for (const Vec3f& q : p.position)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], q[k]);
            hi[k] = std::max(hi[k], q[k]);
        }
    nlohmann::json attr;
    attr["POSITION"] = Accessor(View(Bytes(p.position), n, 12, false, true), kFloat, n, "VEC3",
                                {{"min", {lo.x, lo.y, lo.z}}, {"max", {hi.x, hi.y, hi.z}}});
    attr["NORMAL"] = Accessor(View(Bytes(p.normal), n, 12, false, true), kFloat, n, "VEC3");
    attr["TEXCOORD_0"] = Accessor(View(Bytes(p.atlas_uv), n, 8, false, true), kFloat, n, "VEC2");
    attr["TEXCOORD_1"] = Accessor(View(Bytes(p.chart_uv), n, 8, false, true), kFloat, n, "VEC2");
    if (!p.color.empty())
        attr["COLOR_0"] = Accessor(View(Bytes(p.color), n, 16, false, true), kFloat, n, "VEC4");
    const uint32_t ind = Accessor(View(Bytes(p.indices), p.indices.size(), 4, true, false), kUint32,
                                  p.indices.size(), "SCALAR");
    primitives_.push_back({{"attributes", attr},
                           {"indices", ind},
                           {"material", p.material},
                           {"mode", p.lines ? 1 : 4}});
}

std::vector<uint8_t> WebGlb::Finish() {
    nlohmann::json j;
    j["asset"] = {{"version", "2.0"}, {"generator", "mebake view"}};
    j["scene"] = 0;
    j["scenes"] = {{{"nodes", {0}}}};
    j["nodes"] = {{{"mesh", 0}}};
    j["meshes"] = {{{"primitives", primitives_}}};
    j["materials"] = materials_;
    j["accessors"] = accessors_;
    j["bufferViews"] = views_;
    if (meshopt_) {
        j["buffers"] = {{{"byteLength", bin_.size()}},
                        {{"byteLength", raw_bytes_},
                         {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}}};
        j["extensionsUsed"] = {"EXT_meshopt_compression"};
        j["extensionsRequired"] = {"EXT_meshopt_compression"};
    } else {
        j["buffers"] = {{{"byteLength", bin_.size()}}};
    }
    std::string text = j.dump();
    std::vector<uint8_t> json(text.begin(), text.end());
    Pad4(json, ' ');
    std::vector<uint8_t> out;
    const size_t total = 12 + 8 + json.size() + 8 + bin_.size();
    Append32(out, 0x46546C67);  // "glTF"
    Append32(out, 2);
    Append32(out, uint32_t(total));
    Append32(out, uint32_t(json.size()));
    Append32(out, 0x4E4F534A);  // "JSON"
    out.insert(out.end(), json.begin(), json.end());
    Append32(out, uint32_t(bin_.size()));
    Append32(out, 0x004E4942);  // "BIN"
    out.insert(out.end(), bin_.begin(), bin_.end());
    return out;
}

}  // namespace mebake::view
