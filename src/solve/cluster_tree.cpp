#include "solve/cluster_tree.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mebake::solve {

namespace {

struct Sphere {
    Vec3d c;
    double r = 0;
};

// The smallest sphere holding both.
Sphere Merge(const Sphere& a, const Sphere& b) {
    const double d = Length(b.c - a.c);
    if (d + b.r <= a.r)
        return a;
    if (d + a.r <= b.r)
        return b;
    const double r = 0.5 * (d + a.r + b.r);
    return {a.c + (b.c - a.c) * ((r - a.r) / d), r};
}

}  // namespace

ClusterTree::ClusterTree(std::span<const ChartBound> charts) {
    order_.resize(charts.size());
    for (uint32_t c = 0; c < order_.size(); ++c)
        order_[c] = c;
    if (charts.empty())
        return;
    nodes_.reserve(2 * charts.size() - 1);
    Build(charts, 0, uint32_t(charts.size()));
}

// Node for order_[first, first + count); returns its index. Depth is log2 of the chart
// count (median splits), so the recursion is shallow.
int32_t ClusterTree::Build(std::span<const ChartBound> charts, uint32_t first, uint32_t count) {
    const int32_t index = int32_t(nodes_.size());
    nodes_.emplace_back();
    Node node;
    node.first = first;
    node.count = count;
    auto range = std::span<uint32_t>(order_).subspan(first, count);
    if (count == 1) {
        const ChartBound& b = charts[range[0]];
        node.center = b.center;
        node.radius = b.radius;
        node.max_scale = b.scale;
        nodes_[size_t(index)] = node;
        return index;
    }
    Vec3f lo = charts[range[0]].center, hi = lo;
    for (uint32_t c : range) {
        const Vec3f& p = charts[c].center;
        lo = Vec3f(std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z));
        hi = Vec3f(std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z));
    }
    const Vec3f ext = hi - lo;
    const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
    auto key = [&](uint32_t c) {
        return axis == 0 ? charts[c].center.x : axis == 1 ? charts[c].center.y : charts[c].center.z;
    };
    // A strict total order (ties by chart index): the same tree on every run.
    const uint32_t half = count / 2;
    std::nth_element(range.begin(), range.begin() + half, range.end(), [&](uint32_t a, uint32_t b) {
        const float ka = key(a), kb = key(b);
        return ka < kb || (ka == kb && a < b);
    });
    node.child[0] = Build(charts, first, half);
    node.child[1] = Build(charts, first + half, count - half);
    const Node& a = nodes_[size_t(node.child[0])];
    const Node& b = nodes_[size_t(node.child[1])];
    const Sphere s =
        Merge({Vec3d(a.center), double(a.radius)}, {Vec3d(b.center), double(b.radius)});
    node.center = Vec3f(s.c);
    // Padded by the float rounding of the centre, so the float sphere holds both children.
    const double pad = 4 * std::numeric_limits<float>::epsilon() *
                       (std::max({std::abs(s.c.x), std::abs(s.c.y), std::abs(s.c.z)}) + s.r);
    node.radius = std::nextafter(float(s.r + pad), std::numeric_limits<float>::max());
    node.max_scale = std::max(a.max_scale, b.max_scale);
    nodes_[size_t(index)] = node;
    return index;
}

}  // namespace mebake::solve
