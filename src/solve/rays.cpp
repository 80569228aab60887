#include "solve/rays.h"

#include <atomic>

namespace mebake::solve {

namespace {
// Integer counts: order does not matter.
std::atomic<uint64_t> g_rays[size_t(RayKind::kCount)] = {};
}  // namespace

void SegmentBatch::Trace(const VisibilityScene& vis, RayKind kind) {
    occluded.assign(segments.size(), 0);
    if (segments.empty())
        return;
    vis.Occluded(segments, occluded);
    g_rays[size_t(kind)].fetch_add(segments.size(), std::memory_order_relaxed);
}

void TraceHits(const VisibilityScene& vis, std::span<const Segment> segments, std::span<Hit> hits,
               RayKind kind) {
    if (segments.empty())
        return;
    vis.Intersect(segments, hits);
    g_rays[size_t(kind)].fetch_add(segments.size(), std::memory_order_relaxed);
}

uint64_t TotalRays() {
    uint64_t n = 0;
    for (const auto& r : g_rays)
        n += r.load(std::memory_order_relaxed);
    return n;
}

std::array<uint64_t, size_t(RayKind::kCount)> RaysByKind() {
    std::array<uint64_t, size_t(RayKind::kCount)> out{};
    for (size_t k = 0; k < out.size(); ++k)
        out[k] = g_rays[k].load(std::memory_order_relaxed);
    return out;
}

}  // namespace mebake::solve
