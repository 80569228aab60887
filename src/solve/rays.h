// Shadow segments gathered in batches, so visibility goes to Embree many rays at a time.
#pragma once

#include "core/vec.h"
#include "solve/visibility.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace mebake::solve {

// What a batch of rays is for, counted separately so --stats shows where rays go.
enum class RayKind : int {
    kClassify = 0,  // area lights: lit / umbra / penumbra classification
    kPenumbra,      // area lights: per-cell visibility in penumbrae
    kSky,           // sky directions
    kLink,          // indirect light: receiver point to emitter texel
    kOther,
    kCluster,       // indirect light: visibility samples of a cluster link (cluster_links.cpp)
    kOrigin,        // direct light: a receiver's ray origin moved onto the real surface
    kCount
};
inline constexpr const char* kRayKindNames[] = {"classify", "penumbra", "sky",   "link",
                                                "other",    "cluster",  "origin"};

// A sample's own surface as a link ray sees it (solver.cpp, Gatherer): its real points lie
// within `radius` of the ray's end point on it and within `relief` of the plane through
// `base` with unit normal `n`, which faces the ray's other end.
struct SampleBound {
    Vec3f base, n;
    float radius = 0, relief = 0;
};

struct SegmentBatch {
    std::vector<Segment> segments;
    std::vector<uint8_t> occluded;

    size_t size() const { return segments.size(); }
    void Clear() {
        segments.clear();
        occluded.clear();
    }
    // The segment o + t d, t in (0, tfar).
    void Add(const Vec3f& o, const Vec3f& d, float tfar) {
        segments.push_back(Segment{o.x, o.y, o.z, 0.f, d.x, d.y, d.z, tfar});
    }
    // Segment from a to b, shortened slightly at the far end so b's own surface does
    // not count as a blocker.
    void AddSegment(const Vec3f& a, const Vec3f& b) { Add(a, b - a, 0.999f); }
    // Segment from a receiver point a to an emitter sample's point b, each just above its
    // sample (SampleBound), that leaves out where it is inside both a sample's sphere and
    // its slab: only there may it meet nothing but that sample's own surface, whose shape
    // the pair's transfer already holds. It keeps [0.25, 0.5] at least, so what lies between
    // the samples still blocks; on flat samples (relief below the points' heights) it is
    // AddSegment's segment, and another surface beside a sample (a box standing on it) blocks.
    void AddSegmentBetween(const Vec3f& a, const Vec3f& b, const SampleBound& at_a,
                           const SampleBound& at_b);
    // Fills `occluded` for every segment.
    void Trace(const VisibilityScene& vis, RayKind kind = RayKind::kOther);
};

// Closest hits of `segments` into `hits`, counted as `kind`.
void TraceHits(const VisibilityScene& vis, std::span<const Segment> segments, std::span<Hit> hits,
               RayKind kind);

// Segments traced so far by this process (all threads), for statistics.
uint64_t TotalRays();
// The same per kind.
std::array<uint64_t, size_t(RayKind::kCount)> RaysByKind();

}  // namespace mebake::solve
