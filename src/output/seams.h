// The seam metric: how much the baked lighting jumps across chart borders, where the
// light map is discontinuous by construction (each chart has its own square and field).
// Collocation keeps the seed paper's solution "continuous across the chart boundaries";
// this measures how well, at the display stage, as a viewer sees it.
//
// A seam edge is a mesh edge on the outline of two charts, recognized by the same pair of
// global input vertex ids in both tiles. At `samples` points along it (t = (k + 1/2) / n
// from the lower to the higher vertex id) B is evaluated on each side with that side's own
// uv, normal, colour and material (ChartShader::AtTriangle), and the jump of luminance Y
// (Rec. 709 weights) is compared with the local level:
//   relative jump = |Y1 - Y2| / max((Y1 + Y2) / 2, 1e-3 x mean level over all samples),
// and in display terms (jump_stats.h), which near-black places do not blow up.
// Edges where the surface itself folds (faces more than 45 degrees apart, a box's edge)
// are counted but not measured: B is discontinuous there in any correct solution.
// An edge in more than two charts (non-manifold input) compares the first two; a third
// copy counts as open. Edges with a vertex repair added (no input id) are skipped.
//
// Memory: the outline edges of the charts in progress still waiting for their other side
// (seam_graph.h, BorderPairing); the samples go to a temporary file (12 bytes each) and
// are read back for the means and the exact 95th percentile (a radix selection).
#pragma once

#include "output/bake_view.h"
#include "output/jump_stats.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

namespace mebake::output {

struct SeamOptions {
    int samples = 3;  // points per edge, 1 to 16
};

struct SeamStats {
    uint64_t seam_edges = 0;  // edge pairs compared
    uint64_t open_edges = 0;  // outline edges with no other chart (mesh borders)
    uint64_t fold_edges = 0;  // chart borders on a fold of the surface (not measured)
    uint64_t samples = 0;
    double mean_relative = 0;  // mean relative jump over all samples
    double p95_relative = 0;   // 95th percentile
    double max_relative = 0;
    double mean_level = 0;                // mean luminance of B on seams (W/m^2)
    uint64_t worst_v0 = 0, worst_v1 = 0;  // global vertex ids of the worst edge
    JumpSummary display;                  // the same samples in display terms (jump_stats.h)
};

SeamStats MeasureSeams(const BakeView& view, const SeamOptions& options = {});

// The q-th smallest (from 0) of n > q values >= 0 that for_each(f) passes to f, each pass
// the same values, as std::nth_element finds it, with no copy of them: a radix selection
// on their bits (ordered as the values are, for non-negative doubles), 16 bits per pass,
// four passes. Used for the 95th percentile of the samples spilled to disk.
template <typename ForEach>
double NthSmallest(uint64_t q, ForEach&& for_each) {
    uint64_t prefix = 0;
    std::vector<uint64_t> count(size_t(1) << 16);
    for (int shift = 48; shift >= 0; shift -= 16) {
        std::fill(count.begin(), count.end(), 0);
        const uint64_t high = shift == 48 ? 0 : ~uint64_t(0) << (shift + 16);
        for_each([&](double v) {
            uint64_t bits;
            std::memcpy(&bits, &v, sizeof bits);
            if ((bits & high) == prefix)
                ++count[size_t((bits >> shift) & 0xFFFF)];
        });
        size_t b = 0;
        while (q >= count[b])
            q -= count[b++];
        prefix |= uint64_t(b) << shift;
    }
    double v;
    std::memcpy(&v, &prefix, sizeof v);
    return v;
}

}  // namespace mebake::output
