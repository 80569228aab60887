// Octree construction over triangle centroids, and the segment/box test its queries use.
#include "stream/tile_octree.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace mebake::stream {

namespace {

constexpr int kMaxDepth = 30;  // ForEachLeafOnSegment's stack holds 7 siblings per level

struct Builder {
    std::span<const Vec3f> positions;
    std::span<const std::array<uint32_t, 3>> triangles;
    OctreeOptions options;
    std::vector<Vec3f> centroid;
    TriangleOctree tree;
    std::vector<uint32_t> scratch;

    void TightBox(OctreeNode& n) const {
        n.lo = Vec3f(INFINITY, INFINITY, INFINITY);
        n.hi = Vec3f(-INFINITY, -INFINITY, -INFINITY);
        for (uint32_t i = n.first; i < n.first + n.count; ++i)
            for (uint32_t v : triangles[tree.order[i]]) {
                n.lo = Min(n.lo, positions[v]);
                n.hi = Max(n.hi, positions[v]);
            }
    }

    // Splits node `index` (cell [lo, lo + size]) into the octants of its triangles' centroids.
    void Split(uint32_t index, const Vec3f& lo, float size, int depth) {
        TightBox(tree.nodes[index]);
        const OctreeNode n = tree.nodes[index];
        if (n.count <= options.leaf_triangles || depth >= options.max_depth)
            return;
        const float h = size / 2;
        const Vec3f mid = lo + Vec3f(h, h, h);
        auto octant = [&](uint32_t t) {
            const Vec3f& c = centroid[t];
            return int(c.x >= mid.x) | int(c.y >= mid.y) << 1 | int(c.z >= mid.z) << 2;
        };
        // Stable counting sort of the node's range by octant.
        uint32_t start[9] = {};
        for (uint32_t i = n.first; i < n.first + n.count; ++i)
            ++start[octant(tree.order[i]) + 1];
        for (int k = 0; k < 8; ++k)
            start[k + 1] += start[k];
        scratch.resize(n.count);
        uint32_t fill[8];
        std::copy(start, start + 8, fill);
        for (uint32_t i = n.first; i < n.first + n.count; ++i)
            scratch[fill[octant(tree.order[i])]++] = tree.order[i];
        std::copy(scratch.begin(), scratch.end(), tree.order.begin() + n.first);
        const uint32_t child = uint32_t(tree.nodes.size());
        uint32_t children = 0;
        for (int k = 0; k < 8; ++k)
            if (start[k + 1] > start[k]) {
                OctreeNode c;
                c.first = n.first + start[k];
                c.count = start[k + 1] - start[k];
                tree.nodes.push_back(c);
                ++children;
            }
        tree.nodes[index].child = child;
        tree.nodes[index].children = children;
        uint32_t c = child;
        for (int k = 0; k < 8; ++k)
            if (start[k + 1] > start[k]) {
                const Vec3f clo(k & 1 ? mid.x : lo.x, k & 2 ? mid.y : lo.y, k & 4 ? mid.z : lo.z);
                Split(c++, clo, h, depth + 1);
            }
    }
};

}  // namespace

TriangleOctree BuildTriangleOctree(std::span<const Vec3f> positions,
                                   std::span<const std::array<uint32_t, 3>> triangles,
                                   const OctreeOptions& options) {
    Builder b{positions, triangles, options, {}, {}, {}};
    b.options.leaf_triangles = std::max<uint32_t>(options.leaf_triangles, 1);
    b.options.max_depth = std::clamp(options.max_depth, 0, kMaxDepth);
    if (triangles.empty())
        return {};
    b.centroid.resize(triangles.size());
    Vec3f lo(INFINITY, INFINITY, INFINITY), hi(-INFINITY, -INFINITY, -INFINITY);
    for (size_t t = 0; t < triangles.size(); ++t) {
        const auto& tri = triangles[t];
        b.centroid[t] = (positions[tri[0]] + positions[tri[1]] + positions[tri[2]]) / 3.f;
        lo = Min(lo, b.centroid[t]);
        hi = Max(hi, b.centroid[t]);
    }
    const Vec3f ext = hi - lo;
    // The cube's edge: a little over the largest extent, so the top centroids are inside.
    const float size = std::max({ext.x, ext.y, ext.z, 1e-30f}) * 1.0001f;
    b.tree.order.resize(triangles.size());
    for (uint32_t t = 0; t < triangles.size(); ++t)
        b.tree.order[t] = t;
    OctreeNode root;
    root.count = uint32_t(triangles.size());
    b.tree.nodes.push_back(root);
    b.Split(0, lo, size, 0);
    return std::move(b.tree);
}

std::vector<uint32_t> TriangleOctree::Leaves() const {
    std::vector<uint32_t> out;
    if (nodes.empty())
        return out;
    std::vector<uint32_t> stack{0};
    while (!stack.empty()) {
        const OctreeNode& n = nodes[stack.back()];
        const uint32_t index = stack.back();
        stack.pop_back();
        if (n.children == 0) {
            out.push_back(index);
            continue;
        }
        for (uint32_t c = n.children; c-- > 0;)
            stack.push_back(n.child + c);
    }
    return out;
}

// In double, on a box widened by 1e-4 of its size plus 1e-6 of its distance from the
// origin: Embree's watertight test may report a hit a few ulps outside a triangle.
WideBox WidenBox(const Vec3f& lo, const Vec3f& hi) {
    const double ext = std::max({double(hi.x) - lo.x, double(hi.y) - lo.y, double(hi.z) - lo.z});
    const double far = std::max({std::fabs(double(lo.x)), std::fabs(double(lo.y)),
                                 std::fabs(double(lo.z)), std::fabs(double(hi.x)),
                                 std::fabs(double(hi.y)), std::fabs(double(hi.z))});
    const double margin = 1e-4 * ext + 1e-6 * far + 1e-30;
    return WideBox{{lo.x - margin, lo.y - margin, lo.z - margin},
                   {hi.x + margin, hi.y + margin, hi.z + margin}};
}

SegmentProbe PrepareSegment(const Vec3f& o, const Vec3f& d, float t0, float t1) {
    SegmentProbe s{};
    s.fixed = -1;
    s.tmin = double(t0);
    s.tmax = double(t1);
    if (!(s.tmin <= s.tmax)) {
        s.fixed = s.tmin > s.tmax ? 0 : 1;  // a NaN bound: let the tracer decide
        return s;
    }
    s.tmin -= 1e-6 * std::fabs(s.tmin);
    s.tmax += 1e-6 * std::fabs(s.tmax);
    const float org[3] = {o.x, o.y, o.z}, dir[3] = {d.x, d.y, d.z};
    for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(org[a]) || !std::isfinite(dir[a])) {
            s.fixed = 1;
            return s;
        }
        s.org[a] = org[a];
        s.flat[a] = dir[a] == 0;
        s.inv[a] = s.flat[a] ? 0 : 1.0 / double(dir[a]);
    }
    return s;
}

bool SegmentMayCrossBox(const Vec3f& o, const Vec3f& d, float t0, float t1, const Vec3f& lo,
                        const Vec3f& hi) {
    return MayCross(PrepareSegment(o, d, t0, t1), WidenBox(lo, hi));
}

OctreeRouter::OctreeRouter(const TriangleOctree& tree) : tree_(&tree) {
    boxes_.reserve(tree.nodes.size());
    for (const OctreeNode& n : tree.nodes)
        boxes_.push_back(WidenBox(n.lo, n.hi));
}

void CheckTriangleOctree(const TriangleOctree& tree, size_t triangle_count, const char* file) {
    const FileLoc loc{file};
    if (tree.order.size() != triangle_count)
        CorruptError(loc, "octree orders {} triangles of {}", tree.order.size(), triangle_count);
    if (tree.nodes.empty()) {
        if (triangle_count != 0)
            CorruptError(loc, "octree has no nodes for {} triangles", triangle_count);
        return;
    }
    if (tree.nodes[0].first != 0 || tree.nodes[0].count != triangle_count)
        CorruptError(loc, "octree root covers [{}, +{}) of {} triangles", tree.nodes[0].first,
                     tree.nodes[0].count, triangle_count);
    std::vector<uint8_t> seen(triangle_count, 0);
    std::vector<std::pair<uint32_t, int>> stack{{0, 0}};
    size_t visited = 0;
    while (!stack.empty()) {
        const auto [index, depth] = stack.back();
        stack.pop_back();
        if (++visited > tree.nodes.size() || depth > kMaxDepth)
            CorruptError(loc, "octree node {} is reached twice or too deep", index);
        const OctreeNode& n = tree.nodes[index];
        if (n.children == 0) {
            for (uint32_t i = n.first; i < n.first + n.count; ++i) {
                if (tree.order[i] >= triangle_count || seen[tree.order[i]]++)
                    CorruptError(loc, "octree leaf {} names triangle {} twice or out of range",
                                 index, tree.order[i]);
            }
            continue;
        }
        if (n.children > 8 || n.child <= index || n.child + n.children > tree.nodes.size())
            CorruptError(loc, "octree node {} has children [{}, +{}) of {} nodes", index, n.child,
                         n.children, tree.nodes.size());
        uint32_t next = n.first;
        for (uint32_t c = 0; c < n.children; ++c) {
            const OctreeNode& k = tree.nodes[n.child + c];
            if (k.first != next || k.count == 0)
                CorruptError(loc, "octree node {}'s children do not tile its range", index);
            next += k.count;
            stack.push_back({n.child + c, depth + 1});
        }
        if (next != n.first + n.count)
            CorruptError(loc, "octree node {}'s children do not tile its range", index);
    }
    if (visited != tree.nodes.size())
        CorruptError(loc, "octree has {} nodes, {} reachable", tree.nodes.size(), visited);
}

}  // namespace mebake::stream
