#include "output/continuous_field.h"

#include "core/check.h"
#include "solve/basis.h"

#include <algorithm>
#include <array>

namespace mebake::output {

ContinuousField::ContinuousField(const solve::ChartField& field, double max_delta) : field_(field) {
    double smallest = 1;
    for (const solve::QuadNode& n : field.nodes())
        if (n.leaf())
            smallest = std::min(smallest, n.size());
    delta_ = std::min(0.5 * smallest, max_delta);
}

void ContinuousField::Eval(double u, double v, float* out) const {
    u = std::clamp(u, 0.0, 1.0);
    v = std::clamp(v, 0.0, 1.0);
    const double u0 = std::max(0.0, u - delta_), u1 = std::min(1.0, u + delta_);
    const double v0 = std::max(0.0, v - delta_), v1 = std::min(1.0, v + delta_);
    // The leaves at the box's corners cover it (each is at least 2 delta wide). A corner
    // in a leaf already found is not looked up again (the same leaf LeafAt would give).
    std::array<size_t, 4> leaves{};
    int count = 0;
    double ls, lt;  // a leaf's node-local coordinates
    for (const double cv : {v0, v1})
        for (const double cu : {u0, u1}) {
            bool found = false;
            for (int k = 0; k < count && !found; ++k)
                found = field_.InLeaf(leaves[size_t(k)], cu, cv, &ls, &lt);
            if (!found)
                leaves[size_t(count++)] = field_.LeafAt(cu, cv, &ls, &lt);
        }
    const int blocks = field_.blocks();
    if (count == 1) {  // inside one leaf: its own fit, as ChartField::EvalValue gives it
        if (field_.InLeaf(leaves[0], u, v, &ls, &lt))  // (u, v) lies between the corners
            solve::EvalCoeffs(field_.order(), field_.value(leaves[0]), blocks, ls, lt, out);
        else
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
