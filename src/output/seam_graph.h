// The graph of chart borders and the targets the stitched field meets along them
// (seam_stitch.h). A chart-border edge is a mesh edge on the outline of two charts,
// recognized by the same pair of global input vertex ids in both tiles (as the seam metric,
// seams.h, finds it). Creases (faces, or the charts' shading normals at either end, more than
// 30 degrees apart: Crease, kStitchFoldCos) keep each side's own field, since E and B differ
// there in any correct solution: they enter with zero correction. Mesh borders are left alone.
//
// The rule, as one pass over the tiles in chart order: each chart samples its own shown field
// (continuous_field.h) at n + 1 points along every outline edge, n from the edge's 3D
// length (two samples per texel of the bake's texel size, so both sides choose the same n).
// Pairs meet in chart order; an edge's targets are the means of both sides' samples, and
// the targets at its ends the mean over every chart whose stitched edges meet at that vertex,
// so edges meeting at a vertex agree there. Deterministic (sums in chart order).
//
// Each chart's data is built on demand (SeamStitcher::Chart), from its own tile and those of
// the charts whose boxes touch its box (every chart sharing a vertex with it): the pass
// above is replayed on those charts alone, key by key in chart order, with the pairs taken
// in the order the pass meets them, so the data are the bytes of a pass over every tile.
// Memory: the sampled sides of a chart's neighbourhood, and an LRU of recently sampled
// charts under a fixed byte cap; nothing grows with the total border length.
#pragma once

#include "output/seam_stitch.h"
#include "stream/tile.h"

#include <cstddef>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace mebake::output {

// Two 64-bit ids as a hash-map key: a border edge's input vertices (smaller first), or a
// vertex and a chart.
using IdPair = std::pair<uint64_t, uint64_t>;
struct IdPairHash {
    size_t operator()(const IdPair& k) const {
        uint64_t h = k.first * 0x9E3779B97F4A7C15ull ^ (k.second + 0x632BE59BD9B4E019ull);
        h ^= h >> 31;
        return size_t(h * 0xBF58476D1CE4E5B9ull);
    }
};

struct BakeView;

// An edge used by one triangle of a tile, with both vertices from the input.
struct OutlineEdge {
    uint64_t g0 = 0, g1 = 0;  // global input vertex ids, g0 < g1
    uint32_t v0 = 0, v1 = 0;  // the tile's vertices of g0 and g1
    uint32_t triangle = 0;    // the triangle that uses it
};

// The outline edges of a tile in order of (g0, g1); edges with a vertex repair added (id >=
// vertex_count) are skipped.
std::vector<OutlineEdge> OutlineEdges(const stream::ChartTile& tile, uint64_t vertex_count);

// Unit normal of a tile's triangle (0 for a degenerate one).
Vec3f FaceNormal(const stream::ChartTile& tile, uint32_t triangle);

// Faces more than 45 degrees apart: a fold of the surface, not measured by the seam metric
// (nor stitched: kStitchFoldCos below).
constexpr float kFoldCos = 0.7071f;

// Shading normals more than 30 degrees apart: a crease of the mesh itself. Ingest keeps each
// chart's own vertex normal where it is more than 30 degrees from the brick's
// (stream/chart_builder.cpp, kCreaseCos), so B is discontinuous there in the path tracer as
// in the bake: neither stitched nor measured. (Until session 19 the stitch averaged normals
// up to 45 degrees apart back into one: a point of lucy's beside normals 31 degrees apart went
// from -1.4 % on its own chart to -26 %.)
constexpr float kNormalCreaseCos = 0.8660f;

// The stitch (the field's and the light map's) also leaves borders whose faces are more than
// 30 degrees apart, which the seam metric still measures (under 45): each chart's own field
// was the closer to the path tracer beside them (lucy's point 0.7 texel from a 40-degree
// border: own +0.9 %, stitched +17.6 % toward a neighbour facing the key light more). With
// both rules the point RMS of lucy fell by 0.104 and igea's by 0.047 points, the other scans
// and the Cornell box moved by -0.003 to +0.0004, lucy's pictures by 0.06-0.15 points
// (bench/RESULTS.md, "Issue 13 (session 19)").
constexpr float kStitchFoldCos = 0.8660f;

// A crease between two charts' sides of a border edge: their faces (unit normals fx, fy) with
// a cosine under face_cos, or their shading normals at either end (x0/y0 at g0, x1/y1 at g1)
// more than 30 degrees apart. Each chart's E holds the light above its own horizon and B
// follows its own normal, so the sides differ there in any correct solution: neither the
// field's stitch nor the light map's pulls them together (they pass kStitchFoldCos; the
// metric kFoldCos).
bool Crease(const Vec3f& fx, const Vec3f& fy, const Vec3f& x0, const Vec3f& y0, const Vec3f& x1,
            const Vec3f& y1, float face_cos = kFoldCos);

// Every chart's neighbours, ascending (CSR: chart a's are list[start[a]..start[a + 1])): the
// charts whose boxes touch its box, so every chart sharing a vertex with it, and maybe a few
// more (O(charts^2) box tests).
struct ChartNeighbours {
    std::vector<uint32_t> start, list;
};
ChartNeighbours FindChartNeighbours(const BakeView& view);

// Per chart, the last chart in chart order that can share a border edge with it (itself if
// none comes later).
std::vector<uint32_t> LastNeighbours(const BakeView& view);

// Pairs the sides of chart-border edges as a pass over every tile in chart order meets them
// (the seam metric's and the light map's texel stitch): a key's first side waits; a side of
// the same key from a later chart completes the pair (on_pair(waiting, this), then neither
// waits); a second side from the waiting side's own chart is ignored (a split vertex), a
// third chart's side waits again. A chart's sides still waiting once its last neighbour
// (LastNeighbours) is done can never pair and are dropped as open edges, so memory follows
// the charts in progress, not the whole border: the pairs and their order are the pass's.
template <typename Side>
class BorderPairing {
public:
    explicit BorderPairing(const BakeView& view) : BorderPairing(LastNeighbours(view)) {}
    explicit BorderPairing(const std::vector<uint32_t>& last)
        : keys_(last.size()), retire_at_(last.size()) {
        for (uint32_t a = 0; a < last.size(); ++a)
            retire_at_[last[a]].push_back(a);
    }

    template <typename OnPair>
    void Add(uint32_t c, const IdPair& key, const Side& side, OnPair&& on_pair) {
        const auto it = waiting_.find(key);
        if (it == waiting_.end()) {
            waiting_.emplace(key, Waiting{c, side});
            keys_[c].push_back(key);
            return;
        }
        if (it->second.chart == c)
            return;
        on_pair(it->second.side, side);
        waiting_.erase(it);
    }

    // Chart c's sides are all added: drops the waiting sides of the charts whose last
    // neighbour is c.
    void Done(uint32_t c) {
        for (const uint32_t a : retire_at_[c]) {
            for (const IdPair& key : keys_[a]) {
                const auto it = waiting_.find(key);
                if (it != waiting_.end() && it->second.chart == a) {
                    waiting_.erase(it);
                    ++dropped_;
                }
            }
            std::vector<IdPair>().swap(keys_[a]);
        }
    }

    // The charts whose waiting sides Done(c) drops: no later chart pairs with them.
    const std::vector<uint32_t>& Retired(uint32_t c) const { return retire_at_[c]; }

    // Sides that never paired (so far).
    uint64_t open() const { return dropped_ + waiting_.size(); }
    size_t waiting() const { return waiting_.size(); }

private:
    struct Waiting {
        uint32_t chart;
        Side side;
    };
    std::unordered_map<IdPair, Waiting, IdPairHash> waiting_;
    std::vector<std::vector<IdPair>> keys_;         // per chart: the keys it left waiting
    std::vector<std::vector<uint32_t>> retire_at_;  // per chart c: the charts whose last is c
    uint64_t dropped_ = 0;
};

struct SeamGraphStats {
    uint64_t stitched_edges = 0;  // border edges with targets
    uint64_t fold_edges = 0;      // creases: each side keeps its own field
    uint64_t samples = 0;         // targets over all edges and sides
};

// Builds charts' stitch data on demand and keeps the sampled sides of recently used charts
// (a chart's neighbours are asked for again by the charts around it). A chart's data, once
// built, is kept in an unlinked temporary file and read back when asked for again (every
// output goes through every chart), so it is built once per export. Thread-safe.
class SeamStitcher {
public:
    // `cache_bytes`: the cap of the sampled sides kept between calls. The built data go to
    // a temporary file in `temp_dir` (empty: $TMPDIR, else /tmp).
    SeamStitcher(const BakeView& view, size_t cache_bytes, const std::string& temp_dir = {});
    ~SeamStitcher();
    SeamStitcher(const SeamStitcher&) = delete;
    SeamStitcher& operator=(const SeamStitcher&) = delete;

    // Chart c's stitch data (empty when it has no stitched edge): from the file when built
    // before, else built (Build) and stored.
    std::shared_ptr<const ChartSeams> Chart(const BakeView& view, uint32_t c) const;
    // Builds chart c's stitch data; stats, when given, gets the edges and fold edges whose
    // later side is in c (so sums over charts count each once) and c's samples.
    ChartSeams Build(const BakeView& view, uint32_t c, SeamGraphStats* stats = nullptr) const;
    // Sampled charts served from the cache / sampled again.
    uint64_t hits() const;
    uint64_t misses() const;

    struct Sides;  // one chart's sampled outline sides

private:
    struct Parts;  // a chart's data before its look-up grid is built
    Parts BuildParts(const BakeView& view, uint32_t c, SeamGraphStats* stats) const;
    std::shared_ptr<const Sides> SidesOf(const BakeView& view, uint32_t c) const;

    std::vector<uint32_t> neighbour_start_, neighbours_;  // per chart, CSR, ascending
    size_t cache_bytes_;
    mutable std::mutex mutex_;
    mutable std::list<uint32_t> lru_;  // front: most recent
    struct Entry {
        std::shared_ptr<const Sides> sides;
        std::list<uint32_t>::iterator at;
    };
    mutable std::unordered_map<uint32_t, Entry> cached_;
    mutable size_t cached_bytes_ = 0;
    mutable uint64_t hits_ = 0, misses_ = 0;
    // The built charts' data in the temporary file: offset and size per chart (size 0:
    // not built yet).
    int fd_ = -1;
    mutable std::vector<std::pair<uint64_t, uint64_t>> stored_;
    mutable uint64_t file_end_ = 0;
};

// Every chart's stitch data (index = chart id; empty for a chart without stitched edges),
// chart by chart through a SeamStitcher; stats summed over the charts.
std::vector<ChartSeams> BuildSeamStitch(const BakeView& view, SeamGraphStats* stats = nullptr);

}  // namespace mebake::output
