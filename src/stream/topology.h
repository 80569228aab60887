// Combinatorial topology of a triangle soup held as flat arrays: undirected edge groups,
// half-edge twins, vertex fans, boundary loops, and the report CheckDisc (segment.h) uses
// to decide whether a chart is a topological disc. Shared by repair and segmentation.
//
// Half-edge h = 3 * f + k runs from triangles[f][k] to triangles[f][(k + 1) % 3].
#pragma once

#include "stream/trimesh.h"

#include <array>
#include <cstdint>
#include <vector>

namespace mebake::stream {

constexpr uint32_t kNoIndex = ~uint32_t(0);

// Union-find over [0, n) whose root is always the smallest member, so the result never
// depends on the order the unions were made in.
class DisjointSets {
public:
    explicit DisjointSets(size_t n) : parent_(n) {
        for (size_t i = 0; i < n; ++i)
            parent_[i] = uint32_t(i);
    }
    uint32_t Find(uint32_t x) {
        while (parent_[x] != x) {
            parent_[x] = parent_[parent_[x]];
            x = parent_[x];
        }
        return x;
    }
    // Returns true when a and b were in different sets.
    bool Union(uint32_t a, uint32_t b) {
        a = Find(a);
        b = Find(b);
        if (a == b)
            return false;
        if (a < b)
            parent_[b] = a;
        else
            parent_[a] = b;
        return true;
    }

private:
    std::vector<uint32_t> parent_;
};

// The corner (3 * f + k) of face f at vertex v; kNoIndex if v is not a vertex of f.
inline uint32_t CornerAt(const std::array<uint32_t, 3>& t, uint32_t f, uint32_t v) {
    for (uint32_t k = 0; k < 3; ++k)
        if (t[k] == v)
            return 3 * f + k;
    return kNoIndex;
}

// Half-edges grouped by undirected edge. Groups are ordered by (min vertex, max vertex);
// inside a group half-edges are in increasing id order.
struct EdgeGroups {
    std::vector<uint32_t> halfedge;  // all 3F half-edge ids, grouped
    std::vector<uint32_t> start;     // group g is halfedge[start[g] .. start[g + 1])
    size_t group_count() const { return start.empty() ? 0 : start.size() - 1; }
    size_t group_size(size_t g) const { return start[g + 1] - start[g]; }
};

// Builds the groups. Triangles with a repeated index still contribute their half-edges
// (a zero-length edge forms a group of its own kind, which callers treat as degenerate).
EdgeGroups BuildEdgeGroups(const std::vector<std::array<uint32_t, 3>>& triangles);

// twin[h] = the other half-edge of h's undirected edge when exactly two faces share it,
// kNoIndex otherwise (boundary or non-manifold edge). Orientation is not looked at.
std::vector<uint32_t> BuildTwins(const std::vector<std::array<uint32_t, 3>>& triangles,
                                 const EdgeGroups& groups);

// Vertex -> incident faces, compressed: faces of v are face[offset[v] .. offset[v + 1]),
// increasing. A face with a repeated index is listed once per distinct vertex.
struct VertexFaces {
    std::vector<uint32_t> offset;
    std::vector<uint32_t> face;
};
VertexFaces BuildVertexFaces(const std::vector<std::array<uint32_t, 3>>& triangles,
                             size_t vertex_count);

struct TopologyReport {
    size_t vertices = 0;  // referenced vertices
    size_t edges = 0;
    size_t faces = 0;
    int64_t euler = 0;      // vertices - edges + faces
    size_t components = 0;  // connected through shared vertices
    size_t boundary_edges = 0;
    size_t boundary_loops = 0;
    size_t nonmanifold_edges = 0;     // shared by more than two faces
    size_t nonmanifold_vertices = 0;  // faces around the vertex form more than one fan
    size_t inconsistent_edges = 0;    // two faces traverse the edge in the same direction
    size_t degenerate_faces = 0;      // repeated vertex index

    bool IsManifold() const {
        return nonmanifold_edges == 0 && nonmanifold_vertices == 0 && inconsistent_edges == 0 &&
               degenerate_faces == 0;
    }
    // A topological disc: an oriented 2-manifold, connected, one boundary loop, V-E+F = 1.
    bool IsDisc() const {
        return IsManifold() && faces > 0 && components == 1 && boundary_loops == 1 && euler == 1;
    }
};

// Full topological analysis in O(F log F). Indices must be < vertex_count (CHECKed: every
// TriMesh is built by mebake itself, never straight from a file).
TopologyReport AnalyzeTopology(const TriMesh& mesh);

}  // namespace mebake::stream
