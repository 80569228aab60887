#include "output/continuous_field.h"

#include "core/check.h"
#include "solve/basis.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>

namespace mebake::output {

namespace {

// A leaf's square, [lo_u, hi_u] x [lo_v, hi_v]: its corners (i, j) / 2^level are exact
// doubles (QuadNode::U and V), made here without QuadNode::size()'s division.
struct LeafSquare {
    double lo_u, hi_u, lo_v, hi_v;

    explicit LeafSquare(const solve::QuadNode& q) {
        const double size = std::bit_cast<double>(uint64_t(1023 - q.level) << 52);  // 2^-level
        lo_u = double(q.i) * size, hi_u = (double(q.i) + 1) * size;
        lo_v = double(q.j) * size, hi_v = (double(q.j) + 1) * size;
    }
    // Whether LeafAt would pick this leaf for (u, v) in the unit square: right and top
    // edges excluded but on the chart's border. LeafAt's halving steps are exact, so its
    // leaf is the one whose square holds the point by this rule.
    bool Holds(double u, double v) const {
        return lo_u <= u && (u < hi_u || hi_u == 1) && lo_v <= v && (v < hi_v || hi_v == 1);
    }
};

}  // namespace

ContinuousField::ContinuousField(const solve::ChartField& field, double max_delta) : field_(field) {
    double smallest = 1;
    for (const solve::QuadNode& n : field.nodes())
        if (n.leaf())
            smallest = std::min(smallest, n.size());
    delta_ = std::min(0.5 * smallest, max_delta);
}

size_t ContinuousField::CentreLeaf(double u, double v, double* s, double* t) const {
    // The last leaf this thread found in this field: a texel's neighbour in its row mostly
    // lies in it. LeafAt picks the leaf whose square holds (u, v), right and top edges
    // excluded but on the chart's border (leaves partition the square), and its halving
    // steps are exact, so a leaf that holds the point is LeafAt's answer and
    // (u 2^level - i, v 2^level - j) its exact (s, t). Checked in full, so a stale entry
    // (another field at the same address) is only a miss.
    thread_local const solve::ChartField* last_field = nullptr;
    thread_local size_t last_leaf = 0;
    if (last_field == &field_ && last_leaf < field_.node_count()) {
        const solve::QuadNode& q = field_.node(last_leaf);
        if (q.leaf() && LeafSquare(q).Holds(u, v)) {
            *s = std::clamp(u / q.size() - double(q.i), 0.0, 1.0);
            *t = std::clamp(v / q.size() - double(q.j), 0.0, 1.0);
            return last_leaf;
        }
    }
    last_field = &field_;
    last_leaf = field_.LeafAt(u, v, s, t);
    return last_leaf;
}

void ContinuousField::Eval(double u, double v, float* out) const {
    u = std::clamp(u, 0.0, 1.0);
    v = std::clamp(v, 0.0, 1.0);
    const double u0 = std::max(0.0, u - delta_), u1 = std::min(1.0, u + delta_);
    const double v0 = std::max(0.0, v - delta_), v1 = std::min(1.0, v + delta_);
    const int blocks = field_.blocks();
    // Most boxes lie in the leaf of their centre: then one descent does (below, the same
    // answer from five). A leaf holds the points of its node's square, right and top edges
    // excluded but on the chart's border (LeafAt's halving steps are exact); the square's
    // corners (i, j) / 2^level are exact doubles.
    double centre_s, centre_t;
    const size_t centre = CentreLeaf(u, v, &centre_s, &centre_t);
    const LeafSquare sq(field_.node(centre));
    if (sq.lo_u <= u0 && (u1 < sq.hi_u || sq.hi_u == 1) && sq.lo_v <= v0 &&
        (v1 < sq.hi_v || sq.hi_v == 1)) {
        solve::EvalCoeffs(field_.order(), field_.value(centre), blocks, centre_s, centre_t, out);
        return;
    }
    // The leaves at the box's corners cover it (each is at least 2 delta wide), listed in
    // corner order. A point lies in one leaf by LeafAt's rule, so a corner the centre's
    // leaf holds, or the leaf the last descent found, needs no descent from the root.
    std::array<size_t, 4> leaves{};
    int count = 0;
    size_t found = centre;
    for (const double cv : {v0, v1})
        for (const double cu : {u0, u1}) {
            size_t n = centre;
            if (!sq.Holds(cu, cv)) {
                double cs, ct;
                n = found != centre && LeafSquare(field_.node(found)).Holds(cu, cv)
                        ? found
                        : (found = field_.LeafAt(cu, cv, &cs, &ct));
            }
            if (std::find(leaves.begin(), leaves.begin() + count, n) == leaves.begin() + count)
                leaves[size_t(count++)] = n;
        }
    if (count == 1) {  // inside one leaf: its own fit, as ChartField::EvalValue gives it
        field_.EvalValue(u, v, out);
        return;
    }
    std::fill(out, out + blocks, 0.f);
    double total = 0;
    float part[9];
    CHECK_LE(blocks, 9);
    for (int k = 0; k < count; ++k) {
        const solve::QuadNode& node = field_.node(leaves[size_t(k)]);
        const double lo_u = node.U(0), hi_u = node.U(1), lo_v = node.V(0), hi_v = node.V(1);
        const double w = std::max(0.0, std::min(u1, hi_u) - std::max(u0, lo_u)) *
                         std::max(0.0, std::min(v1, hi_v) - std::max(v0, lo_v));
        if (w <= 0)
            continue;
        // Each leaf is evaluated at the point of its own node nearest to (u, v), never
        // extrapolated past it: extending the fit of a small leaf (its linear terms as well
        // as its quadratic ones) is where the blend went wrong on the scans' pictures
        // (bench/RESULTS.md, issue 14 session 7). Still continuous (the nearest point moves
        // continuously with (u, v)), and the shown value is a convex combination of values
        // the leaves take on their own nodes, so it never overshoots them.
        const double s = std::clamp(u / node.size() - node.i, 0.0, 1.0);
        const double t = std::clamp(v / node.size() - node.j, 0.0, 1.0);
        solve::EvalCoeffs(field_.order(), field_.value(leaves[size_t(k)]), blocks, s, t, part);
        for (int b = 0; b < blocks; ++b)
            out[b] += float(w) * part[b];
        total += w;
    }
    CHECK_GT(total, 0.0);
    for (int b = 0; b < blocks; ++b)
        out[b] = float(out[b] / total);
}

}  // namespace mebake::output
