// glTF 2.0 binary (.glb) output (Khronos, "glTF 2.0 Specification", sections 4.4 and 5)
// for a mesh carrying a baked light map.
//
// Layout: one scene, one node, one mesh with one primitive per BeginPrimitive() (mode 4,
// triangles) whose attributes are POSITION (float VEC3, with min/max), NORMAL (float VEC3,
// unit), TEXCOORD_0 and TEXCOORD_1 (float VEC2, the same accessor: light-map uvs, origin
// at the image's top-left corner as glTF defines), indices uint32. Each material's light
// map is a PNG embedded in the binary chunk. Every buffer view starts on a 4-byte boundary.
//
// How a viewer shows the baked light (GlbLightMapMode):
//   Emissive (default): baseColorFactor black, metallic 0, roughness 1, emissiveTexture =
//     the light map on TEXCOORD_1, emissiveFactor 1. Every core-glTF viewer then displays
//     the baked radiance as is, whatever lights it adds (they only meet a black base).
//   Unlit: KHR_materials_unlit with the light map as baseColorTexture (TEXCOORD_1): exact
//     in viewers that support the extension; others fall back to shading it as albedo.
//
// Vertex data streams to anonymous temporary files as it is added and is copied into the
// .glb at Finish(), so memory holds only the PNGs and the per-primitive bookkeeping.
// A .glb cannot exceed 4 GiB (its length field is 32-bit): Finish() throws Error(Input)
// suggesting PLY or OBJ when it would.
#pragma once

#include "core/vec.h"
#include "io/byte_stream.h"

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace mebake::io {

enum class GlbLightMapMode { Emissive, Unlit };

struct GlbOptions {
    GlbLightMapMode mode = GlbLightMapMode::Emissive;
    std::string temp_dir;  // for the vertex spill files; empty: $TMPDIR or /tmp
    std::string generator = "mebake";
};

class GlbWriter {
public:
    explicit GlbWriter(const GlbOptions& options = {});
    ~GlbWriter();
    GlbWriter(const GlbWriter&) = delete;
    GlbWriter& operator=(const GlbWriter&) = delete;

    // A material showing `png` (an encoded PNG, sRGB) as its light map. Returns its index.
    uint32_t AddLightMapMaterial(std::vector<uint8_t> png, const std::string& name);

    // Starts a new primitive drawn with `material`; the vertices and triangles added next
    // belong to it.
    void BeginPrimitive(uint32_t material);
    // Appends vertices to the current primitive (spans of equal size). Normals are
    // normalized (zero ones become +Z, which glTF's unit-length rule requires). Returns the
    // primitive-local index of the first one.
    uint32_t AddVertices(std::span<const Vec3f> position, std::span<const Vec3f> normal,
                         std::span<const Vec2f> uv);
    // Appends triangles whose indices are primitive-local (CHECKed against the count).
    void AddTriangles(std::span<const std::array<uint32_t, 3>> triangles);
    // Vertices in the current primitive so far (a primitive holds < 2^32 - 1).
    uint64_t primitive_vertices() const;

    // Writes the .glb to `out` and commits it.
    void Finish(OutputStream& out);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace mebake::io
