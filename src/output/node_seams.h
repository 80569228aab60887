// Jumps of the baked lighting across quadtree node borders inside charts: each leaf's
// polynomial is fitted on its own, so neighbouring leaves (at the same or at different
// levels) need not agree on their shared edge. Along the right and top edge of every leaf
// (each edge piece is measured once, from the leaf on its left or below), at `samples`
// points that lie in the chart's real part, B is evaluated just on either side (1e-6 of
// the square away) with the same normal and albedo, so only the field differs, and the
// display jump (jump_stats.h) is recorded.
#pragma once

#include "output/bake_view.h"
#include "output/jump_stats.h"

namespace mebake::output {

struct NodeSeamStats {
    uint64_t edges = 0;  // leaf edges inside the square that were sampled
    JumpSummary display;
};

NodeSeamStats MeasureNodeSeams(const BakeView& view, int samples = 3);

}  // namespace mebake::output
