// A piece of surface held in core — one brick's faces, or one chart — as flat arrays
// with local 32-bit indices. Global ids map every vertex and face back to the input, so
// results can be exported in the input's order. OpenMesh is used inside repair and
// charting only; everything between the passes is this plain struct.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/vec.h"

namespace mebake::stream {

constexpr uint64_t kNoId = ~uint64_t(0);

struct TriMesh {
    std::vector<Vec3f> position;                  // per vertex
    std::vector<Vec3f> albedo;                    // per vertex, linear RGB; empty = none
    std::vector<uint64_t> vertex_id;              // per vertex: global input vertex index
    std::vector<std::array<uint32_t, 3>> triangles;
    std::vector<uint64_t> face_id;                // per triangle: global input triangle
                                                  // index, kNoId if added (hole filling)
    std::vector<uint32_t> material;               // per triangle: scene material index

    size_t vertex_count() const { return position.size(); }
    size_t triangle_count() const { return triangles.size(); }
};

}  // namespace mebake::stream
