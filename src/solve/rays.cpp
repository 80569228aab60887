#include "solve/rays.h"

#include <atomic>

namespace mebake::solve {

namespace {
std::atomic<uint64_t> g_rays{0};  // an integer count: order does not matter
}

void SegmentBatch::Trace(const VisibilityScene& vis) {
    occluded.assign(segments.size(), 0);
    if (segments.empty()) return;
    vis.Occluded(segments, occluded);
    g_rays.fetch_add(segments.size(), std::memory_order_relaxed);
}

uint64_t TotalRays() { return g_rays.load(std::memory_order_relaxed); }

}  // namespace mebake::solve
