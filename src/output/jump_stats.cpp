#include "output/jump_stats.h"

#include "output/tonemap.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mebake::output {

double JumpStats::Display(float y) {
    return EncodeSrgb(ApplyToneCurve(y / float(std::numbers::pi), ToneMap{}));
}

void JumpStats::Add(float y1, float y2) {
    const double d = std::abs(Display(y1) - Display(y2));
    ++n_;
    sum_ += d;
    max_ = std::max(max_, d);
    ++hist_[size_t(std::clamp(int(d * (kBins - 1) + 0.5), 0, kBins - 1))];
}

JumpSummary JumpStats::Summary() const {
    JumpSummary s;
    s.samples = n_;
    if (n_ == 0)
        return s;
    s.mean = sum_ / double(n_);
    s.max = max_;
    const uint64_t rank = uint64_t(std::ceil(0.95 * double(n_)));
    uint64_t seen = 0;
    for (int b = 0; b < kBins; ++b) {
        seen += hist_[size_t(b)];
        if (seen >= rank) {
            s.p95 = double(b) / (kBins - 1);
            break;
        }
    }
    return s;
}

}  // namespace mebake::output
