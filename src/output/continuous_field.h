// A chart's field as displayed: continuous (C0) across quadtree node borders, T-vertices
// included. Each leaf's polynomial is fitted on its own, so neighbouring leaves disagree
// along their shared edge (node_seams.h measures it). The reconstruction
//   E(x) = sum over leaves L of |B(x) n L| / |B(x)| P_L(c_L(x))
// with B(x) the square of half-width delta around x (clipped to the chart's square), P_L
// the leaf's polynomial and c_L(x) the point of L's node nearest to x, has weights and
// arguments that are continuous in x, so E is. A leaf is never extrapolated past its node,
// so E is a convex combination of values the leaves take on their own nodes (no
// overshoot); a field linear across leaves is reproduced to within (|dE/du| + |dE/dv|)
// delta / 8. Farther than delta from its border, a leaf shows its own fit unchanged. delta
// is a constant per chart: half its smallest leaf (so a box meets at most four leaves) and
// at most `max_delta`, about a light-map texel. At a border the value is the mean of the
// two sides.
#pragma once

#include "solve/field.h"

namespace mebake::output {

class ContinuousField {
public:
    ContinuousField(const solve::ChartField& field, double max_delta);

    // The reconstruction at chart point (u, v) (clamped to the square), field.blocks()
    // floats into out.
    void Eval(double u, double v, float* out) const;
    double delta() const { return delta_; }

private:
    // field_.LeafAt(u, v, s, t) for (u, v) in the unit square, the same leaf and (s, t),
    // from the last leaf this thread found when it still holds the point.
    size_t CentreLeaf(double u, double v, double* s, double* t) const;

    const solve::ChartField& field_;
    double delta_ = 0;
};

}  // namespace mebake::output
