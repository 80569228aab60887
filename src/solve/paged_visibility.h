// Visibility beyond memory: the visibility mesh split into spatial pieces, each traced by its
// own Embree scene, built on demand and kept in an LRU under a byte budget (memory-coherent
// ray tracing, Pharr et al. 1997, with the batch of one query call as the unit of coherence:
// the gathers defer their link rays to make calls of thousands, solver.cpp's Resolve).
//
// The pieces are runs of consecutive leaves of an octree over all the triangles
// (stream/tile_octree.h, the same index the tiles carry), so each is spatially compact. A
// query routes each segment through the octree to the leaves whose box it may cross (a
// conservative slab test), and traces each piece so met once, its segments batched:
// - a resident piece is traced by its scene (a hit);
// - a missing one is rented or bought (ski rental): a scene of just the leaves this call's
//   segments cross is built, traced and dropped, until the triangles so built for the piece
//   reach its size; then the whole piece is built into the LRU. So the build work is at most
//   twice what knowing the future would have cost, and small calls (the direct pass brings
//   one quadtree node's rays) do not rebuild whole pieces for a few rays.
// Answers: occlusion is the OR over pieces: a triangle's test does not depend on which scene
// holds it (same flags, watertight test), so the bits equal the whole scene's; closest hit
// is the smallest t over pieces, ties to the lowest (geometry, primitive), inside a piece as
// across them (VisibilityScene::IntersectRanked): the whole scene's answer, ties included
// (its rule is the same). Neither depends on the cache's state, the order pieces are traced
// in or the threads.
//
// Used through VisibilityScene::EnablePaging (visibility.h); nothing else includes this.
#pragma once

#include "solve/visibility.h"
#include "stream/proxy_cluster.h"
#include "stream/tile_octree.h"

#include <atomic>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

namespace mebake::solve {

struct PagingOptions {
    uint64_t cache_bytes = uint64_t(32) << 20;  // Embree bytes of resident pieces (estimated)
    uint32_t piece_triangles = 65536;           // at most this many triangles per piece
};

// Embree bytes per triangle used to size pieces and the cache: ingest's figure for a
// clustered proxy (stream/proxy_cluster.h), above the full mesh's, so either fits.
inline constexpr uint64_t kPieceBytesPerTriangle = stream::kEmbreeBytesPerProxyTriangle;

struct PagingStats {
    uint64_t pieces = 0, largest_piece = 0;  // triangles in the largest piece
    uint64_t segments = 0;  // segments queried
    uint64_t requests = 0;  // (query call, piece) pairs with segments to trace
    uint64_t hits = 0;      // ...whose piece was resident
    uint64_t loads = 0;     // ...that built the whole piece into the LRU (bought)
    uint64_t rentals = 0;   // ...that built a scene of the leaves crossed (rented)
    uint64_t built_triangles = 0;  // triangles of all the scenes built, bought or rented
    uint64_t rays = 0;      // (segment, piece) tests traced
};

class PagedVisibility {
public:
    PagedVisibility(const VisibilityOptions& scene_options, const PagingOptions& options);
    ~PagedVisibility();
    PagedVisibility(const PagedVisibility&) = delete;
    PagedVisibility& operator=(const PagedVisibility&) = delete;

    // Geometry `id` (0, 1, ... in call order, as VisibilityScene numbers them), copied.
    void Add(std::span<const float> positions, std::span<const uint32_t> indices);
    // Splits everything added into pieces (no Embree scene is built yet).
    void Commit();

    void Occluded(std::span<const Segment> segments, std::span<uint8_t> occluded) const;
    void Intersect(std::span<const Segment> segments, std::span<Hit> hits) const;

    PagingStats stats() const;

private:
    struct Piece;
    struct Cached;
    struct Route;
    struct Lease;
    // For each piece, the segments that may cross one of its octree leaves' boxes
    // (ascending) and those leaves.
    void RouteSegments(std::span<const Segment> segments, std::vector<Route>* routes) const;
    // A scene of piece p that holds every triangle of `leaves` (sorted and deduplicated here):
    // the resident scene, the whole piece bought into the LRU, or the leaves rented. The
    // scene stays alive with the lease even if the LRU drops it meanwhile.
    Lease Acquire(uint32_t p, std::vector<uint32_t>* leaves) const;
    std::shared_ptr<const VisibilityScene> BuildPiece(uint32_t p) const;
    // The pieces of `routes` with segments, resident ones first.
    std::vector<uint32_t> TraceOrder(const std::vector<Route>& routes) const;
    void GlobalId(uint32_t triangle, uint32_t* geom, uint32_t* prim) const;

    VisibilityOptions scene_options_;
    PagingOptions options_;
    // What Add received, until Commit splits it into pieces.
    std::vector<float> positions_;
    std::vector<uint32_t> indices_;           // into positions_ (offset per geometry)
    std::vector<uint32_t> geometry_first_;    // first global triangle of each geometry
    std::vector<Piece> pieces_;
    stream::TriangleOctree tree_;             // over all triangles; its leaves route segments
    stream::OctreeRouter router_;             // tree_'s boxes widened for routing
    std::vector<uint32_t> leaf_piece_;        // piece of each node (leaves only)
    std::vector<uint32_t> leaf_first_;        // first local triangle of each leaf in its piece

    mutable std::mutex mutex_;
    mutable std::list<uint32_t> lru_;         // resident pieces, most recent first
    mutable std::vector<Cached> cache_;       // per piece
    mutable uint64_t resident_bytes_ = 0;
    mutable std::atomic<uint64_t> segments_{0}, requests_{0}, hits_{0}, loads_{0}, rentals_{0},
        built_{0}, rays_{0};
};

}  // namespace mebake::solve
