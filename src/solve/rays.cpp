#include "solve/rays.h"

#include <algorithm>
#include <atomic>

namespace mebake::solve {

namespace {
// Integer counts: order does not matter.
std::atomic<uint64_t> g_rays[size_t(RayKind::kCount)] = {};
}  // namespace

void SegmentBatch::AddSegmentToSample(const Vec3f& a, const Vec3f& b, const Vec3f& base,
                                      const Vec3f& n, float radius, float relief) {
    const Vec3f d = b - a;
    const float len = Length(d);
    float t = 0.999f;
    if (len > 0 && radius > 0) {
        const float in_sphere = 1.f - radius / len;
        // The height above the sample's plane falls linearly along the segment: where it
        // comes down to `relief` the segment enters the slab (0: starts in it, 1: never).
        const float ha = Dot(a - base, n), hb = Dot(b - base, n);
        const float in_slab = hb >= relief ? 1.f : ha <= relief ? 0.f : (ha - relief) / (ha - hb);
        t = std::clamp(std::max(in_sphere, in_slab), 0.5f, 0.999f);
    }
    Add(a, d, t);
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
