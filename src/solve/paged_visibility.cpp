// Paged visibility: pieces from an octree, an LRU of piece scenes, queries routed per piece.
#include "solve/paged_visibility.h"

#include "core/check.h"
#include "core/vec.h"
#include "stream/tile_octree.h"

#include <algorithm>
#include <cmath>
#include <malloc.h>

namespace mebake::solve {

struct PagedVisibility::Piece {
    std::vector<float> positions;   // x,y,z per local vertex
    std::vector<uint32_t> indices;  // 3 per triangle, local
    std::vector<uint32_t> global;   // global triangle id per local triangle
};

struct PagedVisibility::Cached {
    std::shared_ptr<const VisibilityScene> scene;  // null: not resident
    std::list<uint32_t>::iterator lru;
    uint64_t bytes = 0;
    uint64_t rented = 0;  // triangles rented since the piece was last resident
};

struct PagedVisibility::Route {
    std::vector<uint32_t> segments;  // ascending
    std::vector<uint32_t> leaves;    // octree leaves crossed (repeats until Acquire)
};

struct PagedVisibility::Lease {
    std::shared_ptr<const VisibilityScene> scene;
    std::span<const uint32_t> global;  // global triangle id of each of the scene's triangles
    std::vector<uint32_t> rented;      // the ids, when the scene is rented
};

PagedVisibility::PagedVisibility(const VisibilityOptions& scene_options,
                                 const PagingOptions& options)
    : scene_options_(scene_options), options_(options) {
    options_.piece_triangles = std::max<uint32_t>(options_.piece_triangles, 1);
}

PagedVisibility::~PagedVisibility() = default;

void PagedVisibility::Add(std::span<const float> positions, std::span<const uint32_t> indices) {
    CHECK(pieces_.empty());
    const uint64_t first_vertex = positions_.size() / 3;
    geometry_first_.push_back(uint32_t(indices_.size() / 3));
    CHECK(first_vertex + positions.size() / 3 < 0xFFFFFFFFu);
    CHECK(indices_.size() / 3 + indices.size() / 3 < 0xFFFFFFFFu);
    positions_.insert(positions_.end(), positions.begin(), positions.end());
    for (uint32_t i : indices)
        indices_.push_back(uint32_t(first_vertex + i));
}

void PagedVisibility::Commit() {
    CHECK(pieces_.empty());
    const size_t nv = positions_.size() / 3, nt = indices_.size() / 3;
    std::vector<Vec3f> pos(nv);
    for (size_t v = 0; v < nv; ++v)
        pos[v] = Vec3f(positions_[3 * v], positions_[3 * v + 1], positions_[3 * v + 2]);
    // Embree ignores triangles with a non-finite vertex; so do the pieces.
    std::vector<std::array<uint32_t, 3>> tris;
    std::vector<uint32_t> global;
    for (uint32_t t = 0; t < nt; ++t) {
        const std::array<uint32_t, 3> tri{indices_[3 * t], indices_[3 * t + 1], indices_[3 * t + 2]};
        bool finite = true;
        for (uint32_t v : tri)
            finite &= std::isfinite(pos[v].x) && std::isfinite(pos[v].y) && std::isfinite(pos[v].z);
        if (finite) {
            tris.push_back(tri);
            global.push_back(t);
        }
    }
    std::vector<float>().swap(positions_);
    std::vector<uint32_t>().swap(indices_);
    // Leaves of 1/64 of a piece (routing is as fine as the leaves' boxes), packed in
    // depth-first order into pieces.
    stream::OctreeOptions oo;
    oo.leaf_triangles = std::max<uint32_t>(options_.piece_triangles / 64, 16);
    oo.max_depth = 20;
    tree_ = stream::BuildTriangleOctree(pos, tris, oo);
    router_ = stream::OctreeRouter(tree_);
    const stream::TriangleOctree& tree = tree_;
    leaf_piece_.assign(tree.nodes.size(), 0);
    leaf_first_.assign(tree.nodes.size(), 0);
    constexpr uint32_t kNone = 0xFFFFFFFFu;
    std::vector<uint32_t> local(nv, kNone);  // a vertex's id in the piece being filled
    std::vector<uint32_t> globals;            // that piece's vertices, by local id
    Piece piece;
    auto finish = [&] {
        if (piece.global.empty())
            return;
        for (uint32_t v : globals)
            local[v] = kNone;
        globals.clear();
        pieces_.push_back(std::move(piece));
        piece = Piece{};
    };
    for (uint32_t leaf : tree.Leaves()) {
        const stream::OctreeNode& n = tree.nodes[leaf];
        if (!piece.global.empty() && piece.global.size() + n.count > options_.piece_triangles)
            finish();
        leaf_piece_[leaf] = uint32_t(pieces_.size());
        leaf_first_[leaf] = uint32_t(piece.global.size());
        for (uint32_t k = n.first; k < n.first + n.count; ++k) {
            const uint32_t t = tree.order[k];
            for (uint32_t v : tris[t]) {
                if (local[v] == kNone) {
                    local[v] = uint32_t(globals.size());
                    globals.push_back(v);
                    piece.positions.insert(piece.positions.end(), {pos[v].x, pos[v].y, pos[v].z});
                }
                piece.indices.push_back(local[v]);
            }
            piece.global.push_back(global[t]);
        }
    }
    finish();
    cache_.resize(pieces_.size());
}

std::shared_ptr<const VisibilityScene> PagedVisibility::BuildPiece(uint32_t p) const {
    const Piece& piece = pieces_[p];
    auto scene = std::make_shared<VisibilityScene>(scene_options_);
    scene->AddTriangles(piece.positions, piece.indices, "visibility piece");
    scene->Commit();
    return scene;
}

PagedVisibility::Lease PagedVisibility::Acquire(uint32_t p, std::vector<uint32_t>* leaves) const {
    const Piece& piece = pieces_[p];
    Lease lease;
    {
        std::lock_guard lock(mutex_);
        Cached& c = cache_[p];
        if (c.scene) {
            hits_.fetch_add(1, std::memory_order_relaxed);
            lru_.splice(lru_.begin(), lru_, c.lru);
            lease.scene = c.scene;
            lease.global = piece.global;
            return lease;
        }
    }
    std::sort(leaves->begin(), leaves->end());
    leaves->erase(std::unique(leaves->begin(), leaves->end()), leaves->end());
    uint64_t triangles = 0;
    for (uint32_t leaf : *leaves)
        triangles += tree_.nodes[leaf].count;
    bool buy = false;
    {
        std::lock_guard lock(mutex_);
        Cached& c = cache_[p];
        c.rented += triangles;
        buy = c.rented >= piece.global.size();
    }
    // Scenes are built outside the lock: Embree's build runs TBB tasks, which may be solver
    // tasks that query this object on this very thread.
    if (!buy) {
        std::vector<float> positions;
        std::vector<uint32_t> indices;
        for (uint32_t leaf : *leaves)
            for (uint32_t k = leaf_first_[leaf]; k < leaf_first_[leaf] + tree_.nodes[leaf].count;
                 ++k) {
                for (int j = 0; j < 3; ++j) {
                    const uint32_t v = piece.indices[3 * size_t(k) + j];
                    indices.push_back(uint32_t(positions.size() / 3));
                    positions.insert(positions.end(), &piece.positions[3 * size_t(v)],
                                     &piece.positions[3 * size_t(v)] + 3);
                }
                lease.rented.push_back(piece.global[k]);
            }
        auto scene = std::make_shared<VisibilityScene>(scene_options_);
        scene->AddTriangles(positions, indices, "visibility piece leaves");
        scene->Commit();
        // Rented scenes are freed at once, but the heap keeps their pages: give them back to
        // the system now and then (16M sphere at --memory 128M: resident
        // after the direct pass 110 -> 76 MiB).
        if (rentals_.fetch_add(1, std::memory_order_relaxed) % 256 == 255)
            malloc_trim(0);
        built_.fetch_add(triangles, std::memory_order_relaxed);
        lease.scene = std::move(scene);
        lease.global = lease.rented;
        return lease;
    }
    auto scene = BuildPiece(p);
    loads_.fetch_add(1, std::memory_order_relaxed);
    built_.fetch_add(piece.global.size(), std::memory_order_relaxed);
    lease.global = piece.global;
    std::vector<std::shared_ptr<const VisibilityScene>> dropped;  // released after the lock
    std::lock_guard lock(mutex_);
    Cached& c = cache_[p];
    c.rented = 0;
    if (c.scene) {  // another thread built it meanwhile
        lru_.splice(lru_.begin(), lru_, c.lru);
        lease.scene = c.scene;
        return lease;
    }
    c.scene = scene;
    lru_.push_front(p);
    c.lru = lru_.begin();
    c.bytes = piece.global.size() * kPieceBytesPerTriangle;
    resident_bytes_ += c.bytes;
    while (resident_bytes_ > options_.cache_bytes && lru_.size() > 1) {
        Cached& old = cache_[lru_.back()];
        lru_.pop_back();
        resident_bytes_ -= old.bytes;
        dropped.push_back(std::move(old.scene));
    }
    lease.scene = std::move(scene);
    return lease;
}

void PagedVisibility::RouteSegments(std::span<const Segment> segments,
                                    std::vector<Route>* routes) const {
    routes->resize(pieces_.size());
    for (Route& r : *routes) {
        r.segments.clear();
        r.leaves.clear();
    }
    for (uint32_t i = 0; i < segments.size(); ++i) {
        const Segment& s = segments[i];
        const Vec3f o(s.ox, s.oy, s.oz), d(s.dx, s.dy, s.dz);
        router_.ForEachLeafOnSegment(o, d, s.tnear, s.tfar, [&](uint32_t leaf) {
            Route& r = (*routes)[leaf_piece_[leaf]];
            if (r.segments.empty() || r.segments.back() != i)
                r.segments.push_back(i);
            r.leaves.push_back(leaf);
        });
    }
}

std::vector<uint32_t> PagedVisibility::TraceOrder(const std::vector<Route>& routes) const {
    std::vector<uint32_t> order;
    for (uint32_t p = 0; p < pieces_.size(); ++p)
        if (!routes[p].segments.empty())
            order.push_back(p);
    std::lock_guard lock(mutex_);
    std::stable_partition(order.begin(), order.end(),
                          [&](uint32_t p) { return cache_[p].scene != nullptr; });
    return order;
}

void PagedVisibility::GlobalId(uint32_t triangle, uint32_t* geom, uint32_t* prim) const {
    const auto it = std::upper_bound(geometry_first_.begin(), geometry_first_.end(), triangle);
    *geom = uint32_t(it - geometry_first_.begin() - 1);
    *prim = triangle - geometry_first_[*geom];
}

void PagedVisibility::Occluded(std::span<const Segment> segments,
                               std::span<uint8_t> occluded) const {
    CHECK_EQ(segments.size(), occluded.size());
    std::fill(occluded.begin(), occluded.end(), uint8_t(0));
    segments_.fetch_add(segments.size(), std::memory_order_relaxed);
    // Per call, not thread_local: while a scene is built, Embree's TBB tasks may run another
    // query on this thread.
    std::vector<Route> routes;
    RouteSegments(segments, &routes);
    std::vector<uint32_t> index;
    std::vector<Segment> batch;
    std::vector<uint8_t> answer;
    // Resident pieces first: a segment they occlude needs no other piece.
    for (uint32_t p : TraceOrder(routes)) {
        index.clear();
        for (uint32_t i : routes[p].segments)
            if (!occluded[i])
                index.push_back(i);
        if (index.empty())
            continue;
        requests_.fetch_add(1, std::memory_order_relaxed);
        rays_.fetch_add(index.size(), std::memory_order_relaxed);
        batch.clear();
        for (uint32_t i : index)
            batch.push_back(segments[i]);
        answer.assign(index.size(), 0);
        Acquire(p, &routes[p].leaves).scene->Occluded(batch, answer);
        for (size_t k = 0; k < index.size(); ++k)
            occluded[index[k]] |= answer[k];
    }
}

void PagedVisibility::Intersect(std::span<const Segment> segments, std::span<Hit> hits) const {
    CHECK_EQ(segments.size(), hits.size());
    std::fill(hits.begin(), hits.end(), Hit{});
    segments_.fetch_add(segments.size(), std::memory_order_relaxed);
    std::vector<Route> routes;
    RouteSegments(segments, &routes);
    std::vector<uint32_t> best(segments.size(), kNoHit);  // global triangle id of hits[i]
    std::vector<Segment> batch;
    std::vector<Hit> answer;
    for (uint32_t p : TraceOrder(routes)) {
        const std::vector<uint32_t>& index = routes[p].segments;
        requests_.fetch_add(1, std::memory_order_relaxed);
        rays_.fetch_add(index.size(), std::memory_order_relaxed);
        batch.clear();
        for (uint32_t i : index)
            batch.push_back(segments[i]);
        answer.assign(index.size(), Hit{});
        const Lease lease = Acquire(p, &routes[p].leaves);
        // Ties inside the piece to the lowest global id too: the whole scene's rule.
        lease.scene->IntersectRanked(batch, answer, lease.global);
        for (size_t k = 0; k < index.size(); ++k) {
            const Hit& h = answer[k];
            if (h.geom_id == kNoHit)
                continue;
            const uint32_t i = index[k], id = lease.global[h.prim_id];
            // The nearest; at equal t the lowest global triangle (a fixed rule, any order).
            if (best[i] != kNoHit && !(h.t < hits[i].t || (h.t == hits[i].t && id < best[i])))
                continue;
            hits[i] = h;
            GlobalId(id, &hits[i].geom_id, &hits[i].prim_id);
            best[i] = id;
        }
    }
}

PagingStats PagedVisibility::stats() const {
    PagingStats st;
    st.pieces = pieces_.size();
    for (const Piece& p : pieces_)
        st.largest_piece = std::max<uint64_t>(st.largest_piece, p.global.size());
    st.segments = segments_.load();
    st.requests = requests_.load();
    st.hits = hits_.load();
    st.loads = loads_.load();
    st.rentals = rentals_.load();
    st.built_triangles = built_.load();
    st.rays = rays_.load();
    return st;
}

}  // namespace mebake::solve
