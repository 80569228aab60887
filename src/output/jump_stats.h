// Jumps of the displayed lighting across a border, summarized the same way for chart
// borders (seams.h) and quadtree node borders (node_seams.h): for a pair of luminances y1,
// y2 of B (Rec. 709 weights) at the same surface point on the two sides,
//   display jump = |D(y1) - D(y2)|, D = the sRGB-encoded default tone map of radiance y / pi:
// the step a viewer sees on the light-map PNG or a render, in [0, 1], which does not blow up
// where B is near zero as a relative jump does. Mean and maximum are exact; the 95th
// percentile comes from a histogram (bins of 1e-4), so memory does not grow with samples.
#pragma once

#include <cstdint>
#include <vector>

namespace mebake::output {

struct JumpSummary {
    uint64_t samples = 0;
    double mean = 0, p95 = 0, max = 0;
};

class JumpStats {
public:
    // Display value of a luminance of B.
    static double Display(float y);

    void Add(float y1, float y2);
    JumpSummary Summary() const;

private:
    static constexpr int kBins = 10001;  // [0, 1] in steps of 1e-4
    uint64_t n_ = 0;
    double sum_ = 0, max_ = 0;
    std::vector<uint64_t> hist_ = std::vector<uint64_t>(kBins, 0);
};

}  // namespace mebake::output
