// A small in-memory glTF 2.0 binary (.glb) writer for the viewer's mesh chunks
// (Khronos, "glTF 2.0 Specification"; EXT_meshopt_compression). Unlike io/gltf_writer.h
// (one streamed file with the light map embedded) a chunk is small and carries what the
// viewer's shader needs per vertex: POSITION, NORMAL, TEXCOORD_0 = atlas uv (origin
// top-left), TEXCOORD_1 = chart uv (the master element's square), and COLOR_0 = the scan's
// colour as read (sRGB-encoded; alpha 0 where the vertex has none). Primitives are
// triangles or line segments (the chart outlines) and name a material whose `extras` hold
// the scene material's parameters.
//
// With `meshopt`, triangles are reordered for the vertex cache and vertices by first use
// (the same mesh; the encoding gains from small deltas), and every buffer view is stored encoded by
// meshoptimizer (meshopt_encodeVertexBuffer / meshopt_encodeIndexBuffer, lossless) under the
// extension EXT_meshopt_compression in the binary chunk (buffer 0), with a fallback buffer 1 that
// has no data (the extension is then required, as its specification allows).
#pragma once

#include "core/vec.h"

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

namespace mebake::view {

struct GlbPrimitive {
    uint32_t material = 0;
    bool lines = false;  // index pairs (mode 1) instead of triangles (mode 4)
    std::vector<Vec3f> position, normal;
    std::vector<Vec2f> atlas_uv, chart_uv;
    std::vector<std::array<float, 4>> color;  // empty: no COLOR_0
    std::vector<uint32_t> indices;
};

class WebGlb {
public:
    explicit WebGlb(bool meshopt) : meshopt_(meshopt) {}

    // A material whose extras are `extras`; returns its index.
    uint32_t AddMaterial(const std::string& name, nlohmann::json extras);
    void AddPrimitive(GlbPrimitive p);  // empty primitives are dropped
    // The whole .glb.
    std::vector<uint8_t> Finish();

private:
    // Appends `bytes` (count elements of `stride` bytes) as a buffer view; returns its index.
    uint32_t View(std::span<const uint8_t> bytes, size_t count, size_t stride, bool indices,
                  bool vertex_data);
    uint32_t Accessor(uint32_t view, uint32_t component, size_t count, const char* type,
                      nlohmann::json extra = nullptr);

    bool meshopt_;
    nlohmann::json materials_ = nlohmann::json::array();
    nlohmann::json views_ = nlohmann::json::array();
    nlohmann::json accessors_ = nlohmann::json::array();
    nlohmann::json primitives_ = nlohmann::json::array();
    std::vector<uint8_t> bin_;
    uint64_t raw_bytes_ = 0;  // the views' size before encoding
};

}  // namespace mebake::view
