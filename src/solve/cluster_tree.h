// A tree of clusters over the charts, for the indirect pass's cluster links (hierarchical
// radiosity with clustering: Smits et al. 1994, Sillion 1995; docs/method.md, Cluster links).
//
// A binary tree of bounding spheres over the charts' root spheres (the geometry pyramids'
// level 0: centre and radius), built top-down by median splits of the chart centres along
// the longest axis of their box. Every leaf holds exactly one chart; nodes[0] is the root.
// The tree depends only on the charts' bounds (ties broken by chart index), so it is the
// same for any thread count and is rebuilt identically when a solve resumes.
#pragma once

#include "core/vec.h"

#include <cstdint>
#include <span>
#include <vector>

namespace mebake::solve {

struct ChartBound {
    Vec3f center;
    float radius = 0;
    double scale = 1;  // the chart square's side in 3D (SolveChart::scale)
};

class ClusterTree {
public:
    struct Node {
        Vec3f center;
        float radius = 0;      // encloses every chart sphere below
        double max_scale = 0;  // largest chart scale below
        uint32_t first = 0;    // the node's charts: charts()[first, first + count)
        uint32_t count = 0;
        int32_t child[2] = {-1, -1};
        bool leaf() const { return child[0] < 0; }
    };

    ClusterTree() = default;
    explicit ClusterTree(std::span<const ChartBound> charts);

    const std::vector<Node>& nodes() const { return nodes_; }
    // Charts in tree order: each node's charts are one contiguous range.
    const std::vector<uint32_t>& charts() const { return order_; }
    std::span<const uint32_t> ChartsOf(const Node& n) const {
        return std::span<const uint32_t>(order_).subspan(n.first, n.count);
    }
    bool empty() const { return nodes_.empty(); }

private:
    int32_t Build(std::span<const ChartBound> charts, uint32_t first, uint32_t count);

    std::vector<Node> nodes_;
    std::vector<uint32_t> order_;
};

}  // namespace mebake::solve
