// A chart tile: everything about one Meshed Master Element, in one chunk_file ("TILE").
//
//   META  ChartMeta                       VPOS  Vec3f per vertex     VNRM  Vec3f per vertex
//   VUV   Vec2f per vertex (in [0,1]^2)   VCOL  Vec3f per vertex (sRGB [0,1]; absent = none)
//   VGID  uint64 global input vertex id   TRIS  3 x uint32 per triangle
//   FGID  uint64 global input triangle id (kNoId for hole fill)   FMAT  packed material id
//   GCST/GCTR/GNST/GNTR/GOUT  the ChartGrid's arrays (point location over the square)
//   GEO0  the finest level of the geometry image (coarser levels are rebuilt on load)
//   OCND/OCTR  the octree of the triangles (tile_octree.h): nodes, triangle order (version 2)
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/vec.h"
#include "stream/chart_grid.h"
#include "stream/geometry_image.h"
#include "stream/tile_octree.h"

namespace mebake::stream {

// 2: the octree chunks (version 1 tiles are refused with a message to ingest again).
constexpr uint32_t kTileVersion = 2;
// The tiles' octrees: leaves of at most this many triangles, at most this deep.
inline constexpr OctreeOptions kTileOctree{32, 12};

struct ChartMeta {
    uint32_t chart = 0, brick = 0;
    uint32_t vertex_count = 0, triangle_count = 0;
    uint32_t resolution = 0;           // light-map texels per side
    uint32_t grid_resolution = 0;
    uint32_t geometry_resolution = 0;  // geometry image texels per side (<= resolution)
    // The solver's finest emitter samples per side at least (a power of two), or 0 for
    // its own rule: a merged chart keeps the sample size its parts had (chart_builder.h).
    uint32_t emitter_resolution = 0;
    double scale = 0;
    double area = 0;
    double jacobian_deviation = 0;
    double jacobian_deviation_max = 0;
    double virtual_fraction = 0;
    Vec3f bbox_min{}, bbox_max{};
    uint32_t flipped = 0;
    uint32_t reserved = 0;
};

struct ChartTile {
    ChartMeta meta;
    std::vector<Vec3f> position, normal;
    std::vector<Vec2f> uv;
    std::vector<Vec3f> color;  // empty when the input had no colours
    std::vector<uint64_t> vertex_id;
    std::vector<std::array<uint32_t, 3>> triangles;
    std::vector<uint64_t> face_id;
    std::vector<uint32_t> material;
    ChartGrid grid;
    GeometryImage geometry;
    TriangleOctree octree;  // read with the mesh; WriteTile builds it from the mesh
};

void WriteTile(const std::string& path, const ChartTile& tile);

enum class TileParts { Everything, GeometryImage, Mesh };
// Reads and checks a tile; throws Error(Corrupt) naming the file and chunk.
ChartTile ReadTile(const std::string& path, TileParts parts = TileParts::Everything);

}  // namespace mebake::stream
