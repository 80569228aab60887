// The one wrapper over Embree 3 (https://www.embree.org): triangle scenes, batched occlusion
// queries for segments (the visibility term V(x,y) of the transport, docs/method.md)
// and closest-hit queries. Nothing else in mebake includes <embree3/rtcore.h>.
//
// What it takes care of, so callers do not have to:
// - ray masks are compiled into this Embree: every ray gets mask 0xFFFFFFFF;
// - flush-to-zero / denormals-are-zero are set for the duration of each query call on the
//   calling thread (TBB workers included) and the caller's MXCSR is restored afterwards, so
//   float results elsewhere do not depend on which thread traced before;
// - vertex buffers are allocated by Embree (padded for its 16-byte loads) and input copied,
//   or shared with the caller, who then provides the padding (AddTrianglesShared);
// - Embree errors become mebake::Error exceptions naming the call, never silent failures;
// - a memory monitor counts Embree's bytes (EmbreeMemoryBytes) and can cap them
//   (SetEmbreeMemoryLimit): a build over the limit throws instead of eating memory.
// Queries are thread-safe after Commit() and deterministic: each segment's answer depends on
// that segment only (occlusion is exact per ray; a closest hit met at the same distance by
// several triangles, e.g. on a shared edge, is the one of lowest (geometry, primitive), so
// it does not depend on the BVH either).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

namespace mebake::solve {

// The segment org + t*dir, t in [tnear, tfar] (tfar may be +inf for a ray). dir need not be
// unit length; t is in units of |dir|. Segments with tnear > tfar are never occluded.
struct Segment {
    float ox = 0, oy = 0, oz = 0, tnear = 0;
    float dx = 0, dy = 0, dz = 0, tfar = 0;
};

inline constexpr uint32_t kNoHit = 0xFFFFFFFFu;

struct Hit {
    float t = 0;                                  // hit distance (in units of |dir|)
    float u = 0, v = 0;                           // barycentrics of vertices 1 and 2
    float ng_x = 0, ng_y = 0, ng_z = 0;           // unnormalized geometric normal (v1-v0)x(v2-v0)
    uint32_t geom_id = kNoHit, prim_id = kNoHit;  // kNoHit when nothing was hit
};

class PagedVisibility;  // paged_visibility.h
struct PagingOptions;

enum class BuildQuality { kLow, kMedium, kHigh };

// How batches are traced. They differ in speed (see bench/embree_rate_bench.cpp for
// numbers on the target machine) and, on an AVX2-only machine, in a few answers: igea's
// solve traced 31922526 rays by stream, 31922524 by packet8, 31911226 one by one
// (bench/RESULTS.md, "Issue 13 (session 16)").
enum class TraceMethod {
    kStream,    // rtcOccluded1M / rtcIntersect1M over chunks of the batch
    kPacket16,  // rtcOccluded16 / rtcIntersect16 (native on AVX-512)
    kPacket8,   // rtcOccluded8 / rtcIntersect8
    kSingle,    // rtcOccluded1 / rtcIntersect1 per segment
};

struct VisibilityOptions {
    // RTC_SCENE_FLAG_COMPACT: smaller BVH (igea: 116 against 151 B per triangle), slower
    // traversal (igea's solve +14 % CPU); a few rays answer differently (solve_job.h).
    bool compact = true;
    bool robust = true;   // RTC_SCENE_FLAG_ROBUST: watertight, no leaks through shared edges
    BuildQuality quality = BuildQuality::kMedium;
    TraceMethod method = TraceMethod::kStream;  // fastest for node-to-node bundles here
    // RTC_INTERSECT_CONTEXT_FLAG_COHERENT for batches of similar rays; used with kStream only
    // (packets ignore it: Embree 3.13.5 can hang in rtcOccluded16 with it, see visibility.cpp).
    // Not for the solver either: with it, the gen1m M2 solve did not finish in 16 CPU-minutes
    // (it takes 19 CPU-seconds without), November 2026.
    bool coherent = false;
};

class VisibilityScene {
public:
    explicit VisibilityScene(const VisibilityOptions& options = {});
    ~VisibilityScene();
    VisibilityScene(const VisibilityScene&) = delete;
    VisibilityScene& operator=(const VisibilityScene&) = delete;

    // Adds a triangle mesh, copied: positions x,y,z per vertex, indices 3 per triangle.
    // Returns its geometry id (0, 1, ... in call order). Throws InputError for malformed
    // input (sizes, indices out of range); triangles with non-finite vertices are ignored.
    // `name` is used in error messages.
    uint32_t AddTriangles(std::span<const float> positions, std::span<const uint32_t> indices,
                          const char* name = "mesh");

    // Same without copying: Embree reads the caller's arrays, which must stay alive and
    // unchanged until this scene is destroyed. positions holds x,y,z for vertex_count vertices
    // plus at least one spare float (Embree's 16-byte loads read past the last vertex).
    // Shared arrays are the caller's memory and are not counted by EmbreeMemoryBytes().
    uint32_t AddTrianglesShared(std::span<const float> positions, size_t vertex_count,
                                std::span<const uint32_t> indices, const char* name = "mesh");

    // Paged mode, set before anything is added: the triangles are kept (copied) and split
    // into spatial pieces at Commit, whose Embree scenes are built when a query needs them and
    // kept in an LRU of paging.cache_bytes (paged_visibility.h). Same answers as one scene.
    void EnablePaging(const PagingOptions& paging);
    // The pieces and their statistics in paged mode; null otherwise.
    const PagedVisibility* paged() const { return paged_.get(); }

    // Builds the BVH (in paged mode: the pieces). Throws Error if Embree fails (e.g. over the
    // memory limit).
    void Commit();

    // occluded[i] = 1 if a triangle intersects segment i, else 0. Thread-safe after Commit.
    void Occluded(std::span<const Segment> segments, std::span<uint8_t> occluded) const;
    // Same, parallel over chunks of the batch through core/parallel.h.
    void OccludedParallel(std::span<const Segment> segments, std::span<uint8_t> occluded) const;

    // Closest hit in [tnear, tfar] per segment; at equal t the lowest (geometry, primitive).
    // Thread-safe after Commit.
    void Intersect(std::span<const Segment> segments, std::span<Hit> hits) const;
    // The same for a scene of one geometry (not paged), ties going to the lowest
    // rank[primitive] instead (a paged piece's global triangle ids); empty rank: Intersect.
    void IntersectRanked(std::span<const Segment> segments, std::span<Hit> hits,
                         std::span<const uint32_t> rank) const;

    uint64_t triangle_count() const { return triangles_; }
    const VisibilityOptions& options() const { return options_; }

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::unique_ptr<PagedVisibility> paged_;
    VisibilityOptions options_;
    uint64_t triangles_ = 0;
    bool committed_ = false;
    uint32_t geometries_ = 0;
};

// Bytes Embree holds right now (all scenes of the process), and the largest value seen.
int64_t EmbreeMemoryBytes();
int64_t EmbreePeakMemoryBytes();
// Embree operations that would push EmbreeMemoryBytes() over `bytes` fail with an Error
// (0 = no limit). Meant for the caller's memory budget (docs/architecture.md, Memory).
void SetEmbreeMemoryLimit(int64_t bytes);

// Sets the limit for its lifetime and restores the previous one.
class EmbreeMemoryCap {
public:
    explicit EmbreeMemoryCap(uint64_t bytes);
    ~EmbreeMemoryCap();
    EmbreeMemoryCap(const EmbreeMemoryCap&) = delete;
    EmbreeMemoryCap& operator=(const EmbreeMemoryCap&) = delete;

private:
    int64_t previous_;
};

}  // namespace mebake::solve
