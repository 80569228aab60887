// The visibility proxy under a triangle budget, by vertex clustering on one global grid
// (Rossignac & Borrel 1993, "Multi-resolution 3D approximations for rendering complex
// scenes"): every input vertex falls into a cubic cell, the cell's representative is the
// mean of its vertices, and an input triangle survives only if its three vertices lie in
// three different cells. The surface arrives in parts (ingest's bricks) that are read
// one at a time (the next one read meanwhile), twice per round, so memory follows the
// budget, not the input:
//   round pass A  per part: sum the vertices per cell, in integer fixed point, so the
//                 sum (hence the representative) does not depend on the order of the
//                 parts or the vertices; a vertex shared by two parts (a brick border)
//                 lands in the same cell with the same representative: no cracks
//   round pass B  per part: map triangles to cells, keep those with three different
//                 cells; of several on the same three cells one is kept, whatever their
//                 orientation (a wall thinner than a cell becomes one sheet, not nothing:
//                 cancelling opposite pairs would keep the mesh closed but let light
//                 through thin walls)
// The first cell size follows from the surface area and the budget; a round that ends
// over the budget is redone with a larger cell.
//
// Deviation: the largest distance of an input vertex from its cell's representative.
// Every proxy triangle is the image of an input triangle under the vertex -> representative
// map, so every proxy point lies within this distance of the input surface (what the
// solver's ray offset needs), and every input vertex lies within it of the proxy when its
// cell is a corner of some proxy triangle (uncovered_vertices counts those whose cell is
// not: pieces smaller than a cell that collapsed entirely).
#pragma once

#include "core/vec.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace mebake::stream {

// The solver's Embree scene must fit the budget's visibility share
// (core/memory_budget.h). Embree's peak cost per triangle, measured (solve --stats
// embree_bytes, mkscan spheres): the full mesh 55 B (55.4 MB for 1M, 219 MB for 4M), a
// clustered proxy 88-101 B (86.9 MB for 986K, 72.6 MB for 721K; its triangles are less
// regular), so 100 B. At the default 1 GiB: the full mesh up to 1.2M triangles, else a
// proxy of at most 670K.
inline constexpr uint64_t kEmbreeBytesPerTriangle = 56;
inline constexpr uint64_t kEmbreeBytesPerProxyTriangle = 100;
inline uint64_t FullMeshTriangleBudget(uint64_t visibility_bytes) {
    return visibility_bytes / kEmbreeBytesPerTriangle;
}
inline uint64_t ProxyTriangleBudget(uint64_t visibility_bytes) {
    return visibility_bytes / kEmbreeBytesPerProxyTriangle;
}

struct ProxyMesh {
    std::vector<Vec3f> positions;
    std::vector<uint32_t> triangles;  // 3 indices per triangle
};

// Returns part k (0 <= k < parts) of the input surface. Called several times per part.
using ProxyPartSource = std::function<ProxyMesh(uint32_t part)>;

struct ClusterOptions {
    uint64_t max_triangles = 0;    // the budget (at least 1)
    double surface_area = 0;       // of the input; sets the first cell size
    Vec3d bbox_min{}, bbox_max{};  // contains every input vertex
};

struct ClusterResult {
    ProxyMesh mesh;        // vertices in cell order, triangles sorted
    double cell_size = 0;  // edge of the grid's cubes
    double deviation = 0;  // see the top of this file
    uint64_t input_triangles = 0;
    uint64_t uncovered_vertices = 0;
    int rounds = 0;
};

// Deterministic: the result does not depend on the thread count or on the order of the
// parts (a vertex copied into two parts counts twice in its cell's mean, as in both
// bricks it borders). Throws what `source` throws.
ClusterResult ClusterProxy(uint32_t parts, const ProxyPartSource& source,
                           const ClusterOptions& opt);

}  // namespace mebake::stream
