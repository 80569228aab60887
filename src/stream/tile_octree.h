// An octree over a set of triangles: the 3D index each chart tile carries (chunks OCND and
// OCTR, docs/file-formats.md), and the spatial split of the visibility mesh into the pieces
// the paged visibility traces (solve/paged_visibility.h).
//
// Cells halve the cube around the triangles' centroids; a triangle belongs to the cell of its
// centroid, so every triangle is in exactly one leaf. The node boxes are the tight boxes of
// their triangles' vertices (they may overlap a neighbour's), so a query that misses a node's
// box misses all its triangles. Deterministic: the order of the nodes and triangles depends
// on the input only (a stable partition by octant, children in octant order).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <span>
#include <vector>

#include "core/vec.h"

namespace mebake::stream {

struct OctreeNode {
    Vec3f lo{}, hi{};        // tight box of the node's triangles
    uint32_t first = 0;      // the node's triangles: order[first, first + count)
    uint32_t count = 0;
    uint32_t child = 0;      // index of the first child (children are contiguous); 0: a leaf
    uint32_t children = 0;   // number of children (1..8; 0 for a leaf)
};
static_assert(sizeof(OctreeNode) == 40, "OctreeNode is written as raw bytes");

struct TriangleOctree {
    std::vector<OctreeNode> nodes;  // nodes[0] is the root (absent when there are no triangles)
    std::vector<uint32_t> order;    // triangle indices, each leaf's contiguous

    bool empty() const { return nodes.empty(); }
    // The leaves in depth-first order (children in octant order): spatially coherent runs.
    std::vector<uint32_t> Leaves() const;
};

// SegmentMayCrossBox's test in two halves, for routing many segments through many boxes:
// a box widened once (WideBox), a segment prepared once (SegmentProbe, its reciprocal
// direction), then each test is a few multiplications.
struct WideBox {
    double lo[3], hi[3];
};
WideBox WidenBox(const Vec3f& lo, const Vec3f& hi);
struct SegmentProbe {
    double org[3], inv[3];  // inv = 1 / dir where dir != 0
    bool flat[3];           // dir == 0 on this axis
    double tmin, tmax;      // the parameter range, widened
    int fixed;              // -1: test boxes; 0 / 1: the answer for every box
};
SegmentProbe PrepareSegment(const Vec3f& o, const Vec3f& d, float t0, float t1);
// The slab test (inline: the paged visibility's routing makes tens of them per segment).
// (lo - o) * inv may differ from (lo - o) / d by an ulp of a double, far below the box's
// margin and the range's widening.
inline bool MayCross(const SegmentProbe& s, const WideBox& b) {
    if (s.fixed >= 0)
        return s.fixed == 1;
    double tmin = s.tmin, tmax = s.tmax;
    for (int a = 0; a < 3; ++a) {
        if (s.flat[a]) {
            if (s.org[a] < b.lo[a] || s.org[a] > b.hi[a])
                return false;
            continue;
        }
        double ta = (b.lo[a] - s.org[a]) * s.inv[a], tb = (b.hi[a] - s.org[a]) * s.inv[a];
        if (ta > tb)
            std::swap(ta, tb);
        tmin = std::max(tmin, ta);
        tmax = std::min(tmax, tb);
        if (tmin > tmax)
            return false;
    }
    return true;
}

// Leaf queries over an octree, its node boxes widened once (the tree must outlive it).
class OctreeRouter {
public:
    OctreeRouter() = default;
    explicit OctreeRouter(const TriangleOctree& tree);
    // Calls visit(leaf) for every leaf whose box the segment o + t d, t in [t0, t1], may
    // cross (SegmentMayCrossBox), in depth-first order.
    template <typename Visit>
    void ForEachLeafOnSegment(const Vec3f& o, const Vec3f& d, float t0, float t1,
                              Visit&& visit) const;

private:
    const TriangleOctree* tree_ = nullptr;
    std::vector<WideBox> boxes_;  // per node
};

struct OctreeOptions {
    uint32_t leaf_triangles = 32;  // a node with more is split...
    int max_depth = 12;            // ...unless it is this deep
};

TriangleOctree BuildTriangleOctree(std::span<const Vec3f> positions,
                                   std::span<const std::array<uint32_t, 3>> triangles,
                                   const OctreeOptions& options = {});

// Whether the segment o + t d, t in [t0, t1], may cross the box [lo, hi]: the slab test,
// widened by a relative margin so that a ray grazing a face is never culled by rounding.
bool SegmentMayCrossBox(const Vec3f& o, const Vec3f& d, float t0, float t1, const Vec3f& lo,
                        const Vec3f& hi);

// Throws Error(Corrupt) naming `file` unless the octree is well formed over `triangle_count`
// triangles (node ranges nested, children in range, every triangle in exactly one leaf).
void CheckTriangleOctree(const TriangleOctree& tree, size_t triangle_count, const char* file);

template <typename Visit>
void OctreeRouter::ForEachLeafOnSegment(const Vec3f& o, const Vec3f& d, float t0, float t1,
                                        Visit&& visit) const {
    if (!tree_ || tree_->nodes.empty())
        return;
    const SegmentProbe probe = PrepareSegment(o, d, t0, t1);
    if (probe.fixed == 0)
        return;
    uint32_t stack[8 * 32];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const uint32_t index = stack[--top];
        if (probe.fixed < 0 && !MayCross(probe, boxes_[index]))
            continue;
        const OctreeNode& n = tree_->nodes[index];
        if (n.children == 0) {
            visit(index);
            continue;
        }
        for (uint32_t c = n.children; c-- > 0;)  // pushed in reverse: popped in octant order
            stack[top++] = n.child + c;
    }
}

}  // namespace mebake::stream
