#include "solve/rays.h"

#include <algorithm>
#include <atomic>

namespace mebake::solve {

namespace {
// Integer counts: order does not matter.
std::atomic<uint64_t> g_rays[size_t(RayKind::kCount)] = {};
}  // namespace

namespace {

// Where a segment of length `len` starting at a sample's point leaves that sample's sphere
// and slab (SampleBound), as a fraction of its length: h0, h1 are its heights above the
// sample's plane at its start and end (h0 below h1). 0: it starts outside either.
float LeavesSample(const SampleBound& s, float len, float h0, float h1) {
    if (s.radius <= 0 || h0 >= s.relief)
        return 0.f;
    const float out_slab = h1 <= s.relief ? 1.f : (s.relief - h0) / (h1 - h0);
    return std::min(s.radius / len, out_slab);
}

}  // namespace

void SegmentBatch::AddSegmentBetween(const Vec3f& a, const Vec3f& b, const SampleBound& at_a,
                                     const SampleBound& at_b) {
    const Vec3f d = b - a;
    const float len = Length(d);
    if (len <= 0) {
        Add(a, d, 0.999f);
        return;
    }
    // The heights above each sample's plane run linearly along the segment.
    const float near = LeavesSample(at_a, len, Dot(a - at_a.base, at_a.n), Dot(b - at_a.base, at_a.n));
    const float far = LeavesSample(at_b, len, Dot(b - at_b.base, at_b.n), Dot(a - at_b.base, at_b.n));
    segments.push_back(Segment{a.x, a.y, a.z, std::min(near, 0.25f), d.x, d.y, d.z,
                               std::clamp(1.f - far, 0.5f, 0.999f)});
}

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
