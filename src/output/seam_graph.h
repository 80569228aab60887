// The graph of chart borders and the targets the stitched field meets along them
// (seam_stitch.h). A chart-border edge is a mesh edge on the outline of two charts,
// recognized by the same pair of global input vertex ids in both tiles (as the seam metric,
// seams.h, finds it). Creases (faces, or the charts' shading normals at either end, more than
// 45 degrees apart) keep each side's own field, since E and B differ there in any correct
// solution: they enter with zero correction. Mesh borders are left alone.
//
// One pass over the tiles (in batches, ForEachTile): each chart samples its own shown field
// (continuous_field.h) at n + 1 points along every outline edge, n from the edge's 3D
// length (two samples per texel of the bake's texel size, so both sides choose the same n).
// Pairs meet in chart order; an edge's targets are the means of both sides' samples, and
// the targets at its ends the mean over every chart whose stitched edges meet at that vertex,
// so edges meeting at a vertex agree there. Deterministic (sums in chart order).
//
// Memory: the outline edges still waiting for their other side, and the finished targets
// (n + 1 samples of 3 or 9 floats per border edge and side): it grows with the total length
// of the chart borders, not with the mesh.
#pragma once

#include "output/seam_stitch.h"
#include "stream/tile.h"

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace mebake::output {

// Two 64-bit ids as a hash-map key: a border edge's input vertices (smaller first), or a
// vertex and a chart.
using IdPair = std::pair<uint64_t, uint64_t>;
struct IdPairHash {
    size_t operator()(const IdPair& k) const {
        uint64_t h = k.first * 0x9E3779B97F4A7C15ull ^ (k.second + 0x632BE59BD9B4E019ull);
        h ^= h >> 31;
        return size_t(h * 0xBF58476D1CE4E5B9ull);
    }
};

struct BakeView;

// An edge used by one triangle of a tile, with both vertices from the input.
struct OutlineEdge {
    uint64_t g0 = 0, g1 = 0;  // global input vertex ids, g0 < g1
    uint32_t v0 = 0, v1 = 0;  // the tile's vertices of g0 and g1
    uint32_t triangle = 0;    // the triangle that uses it
};

// The outline edges of a tile in order of (g0, g1); edges with a vertex repair added (id >=
// vertex_count) are skipped.
std::vector<OutlineEdge> OutlineEdges(const stream::ChartTile& tile, uint64_t vertex_count);

// Unit normal of a tile's triangle (0 for a degenerate one).
Vec3f FaceNormal(const stream::ChartTile& tile, uint32_t triangle);

// Faces more than 45 degrees apart: a fold of the surface, not stitched nor measured.
constexpr float kFoldCos = 0.7071f;

// A crease between two charts' sides of a border edge: their faces (unit normals fx, fy), or
// their shading normals at either end (x0/y0 at g0, x1/y1 at g1), more than 45 degrees
// apart. Each chart's E holds the light above its own horizon and B follows its own normal,
// so the sides differ there in any correct solution: neither the field's stitch nor the
// light map's pulls them together.
bool Crease(const Vec3f& fx, const Vec3f& fy, const Vec3f& x0, const Vec3f& y0, const Vec3f& x1,
            const Vec3f& y1);

struct SeamGraphStats {
    uint64_t stitched_edges = 0;  // border edges with targets
    uint64_t fold_edges = 0;      // creases: each side keeps its own field
    uint64_t samples = 0;         // targets over all edges and sides
};

// Every chart's stitch data (index = chart id; empty for a chart without stitched edges).
std::vector<ChartSeams> BuildSeamStitch(const BakeView& view, SeamGraphStats* stats = nullptr);

}  // namespace mebake::output
