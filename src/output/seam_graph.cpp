#include "output/seam_graph.h"

#include "core/check.h"
#include "core/error.h"
#include "core/temp_file.h"
#include "output/bake_view.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <type_traits>
#include <unordered_set>

#include <unistd.h>

namespace mebake::output {

namespace {

constexpr double kSamplesPerTexel = 2;
constexpr uint32_t kMaxIntervals = 64;
constexpr double kMinBandTexels = 2, kMaxBandTexels = 3;
constexpr double kBrightPower = 4;  // brightness 2x -> weight 16x

using Key = IdPair;
using KeyHash = IdPairHash;

// One chart's side of an outline edge: where it lies in the chart and its field along it.
struct Side {
    uint32_t chart = 0;
    Vec2f a, b;  // uv of g0 and g1
    float band = 0;
    Vec3f normal;             // of the face beside the edge
    uint32_t v0 = 0, v1 = 0;  // the tile's vertices of g0 and g1
    Vec3f n0, n1;             // their shading normals
    uint32_t intervals = 0;   // samples at t = k / intervals, k = 0..intervals
    const float* vals = nullptr;  // (intervals + 1) x blocks, in its Sides' vals
};

}  // namespace

struct SeamStitcher::Sides {
    Sides() = default;
    Sides(Sides&&) = default;  // moves keep vals' buffer, so the sides' pointers stay valid
    Sides(const Sides&) = delete;
    std::vector<Key> keys;  // in the order of OutlineEdges
    std::vector<Side> sides;
    std::vector<float> vals;  // every side's samples, one block: no allocation per side
    size_t bytes = 0;         // what its arrays hold, as allocated (the LRU's measure)
};

namespace {

using ChartSides = SeamStitcher::Sides;

ChartSides SampleSides(const BakeView& view, uint32_t c, const stream::ChartTile& tile,
                       int blocks) {
    ChartSides out;
    const auto field = view.Field(c);
    const double res = double(std::max<uint32_t>(1, tile.meta.resolution));
    const ContinuousField shown(*field, 1.0 / res);
    const double texel = view.manifest.texel_size;
    std::vector<size_t> firsts;  // each side's first sample in out.vals
    for (const OutlineEdge& e : OutlineEdges(tile, view.manifest.vertex_count)) {
        Side s;
        s.chart = c;
        s.a = tile.uv[e.v0];
        s.b = tile.uv[e.v1];
        s.normal = FaceNormal(tile, e.triangle);
        s.v0 = e.v0;
        s.v1 = e.v1;
        s.n0 = tile.normal[e.v0];
        s.n1 = tile.normal[e.v1];
        const double len = Length(Vec3d(tile.position[e.v1]) - Vec3d(tile.position[e.v0]));
        s.intervals = texel > 0 ? uint32_t(std::clamp(std::ceil(kSamplesPerTexel * len / texel),
                                                      1.0, double(kMaxIntervals)))
                                : 1;
        const Vec2f mid = (s.a + s.b) * 0.5f;
        double ls, lt;
        const double leaf = field->node(field->LeafAt(mid.x, mid.y, &ls, &lt)).size();
        s.band = float(std::clamp(0.5 * leaf, kMinBandTexels / res, kMaxBandTexels / res));
        const size_t first = out.vals.size();
        out.vals.resize(first + size_t(s.intervals + 1) * size_t(blocks));
        for (uint32_t k = 0; k <= s.intervals; ++k) {
            const double t = double(k) / double(s.intervals);
            shown.Eval(s.a.x + t * (s.b.x - s.a.x), s.a.y + t * (s.b.y - s.a.y),
                       &out.vals[first + size_t(k) * size_t(blocks)]);
        }
        firsts.push_back(first);  // pointed at once vals stops growing
        out.keys.push_back({e.g0, e.g1});
        out.sides.push_back(s);
    }
    out.keys.shrink_to_fit();
    out.sides.shrink_to_fit();
    out.vals.shrink_to_fit();
    for (size_t i = 0; i < out.sides.size(); ++i)
        out.sides[i].vals = out.vals.data() + firsts[i];
    out.bytes = out.keys.capacity() * sizeof(Key) + out.sides.capacity() * sizeof(Side) +
                out.vals.capacity() * sizeof(float);
    return out;
}

// An end of a stitched edge in one chart.
struct End {
    uint64_t g;
    uint32_t v;       // the tile's vertex
    Vec3f normal;     // its shading normal there
    uint32_t target;  // index of the edge's target sample at this end
};

// Per vertex: the sums of the charts' E and shading normals there (each chart once).
struct VertexSum {
    std::vector<double> e;
    double weight = 0;
    Vec3d normal{};
    uint32_t n = 0;
};

// Weight of a side's value in a target: its brightness as shown (luminance of n . E with
// the side's shading normal n, or of B for a radiosity solution) to the power kBrightPower,
// so a side much darker than the other counts little. Where two charts disagree much, the
// darker one is nearly always the wrong one (light lost to occluded virtual points, a shadow
// line one chart misplaced); see docs/export.md.
double Weight(const float* v, const Vec3f& n, int blocks) {
    const float w[3] = {0.2126f, 0.7152f, 0.0722f};
    double y = 0;
    for (int c = 0; c < 3; ++c)
        y += w[c] * (blocks == 3 ? v[c] : n.x * v[3 * c] + n.y * v[3 * c + 1] + n.z * v[3 * c + 2]);
    return std::pow(std::max(y, 1e-6), kBrightPower);
}

// The vertex sums of chart c's edge ends: each chart's value once per vertex (the first
// side met), in the order the pass meets the pairs.
struct VertexSums {
    std::unordered_map<uint64_t, VertexSum> sum;
    std::unordered_set<Key, KeyHash> counted;  // (vertex, chart) already in `sum`

    void Add(uint64_t g, const Side& s, bool last, int blocks) {
        if (!counted.insert({g, s.chart}).second)
            return;
        VertexSum& v = sum[g];
        v.e.resize(size_t(blocks), 0.0);
        const float* val = &s.vals[size_t(last ? s.intervals : 0) * size_t(blocks)];
        const double w = Weight(val, Normalize(last ? s.n1 : s.n0), blocks);
        for (int b = 0; b < blocks; ++b)
            v.e[size_t(b)] += w * double(val[b]);
        v.weight += w;
        v.normal += Vec3d(last ? s.n1 : s.n0);
        ++v.n;
    }
};

// A side of the neighbourhood: slot of its chart (charts ascending) and index in its sides.
struct At {
    uint32_t slot = 0, index = 0;
};

// A border edge of two charts: y is the side the pass meets second (it pairs with x,
// waiting). A crease keeps each side's own samples as its targets.
struct Pair {
    At x, y;
    bool crease = false;
};

}  // namespace

// A scan's hard edge with a normal per side was stitched as one surface: nefertiti's crown
// showed 0.61 where the path tracer has 1.84 (bench/RESULTS.md, "Issue 14 (session 8)").
bool Crease(const Vec3f& fx, const Vec3f& fy, const Vec3f& x0, const Vec3f& y0, const Vec3f& x1,
            const Vec3f& y1, float face_cos) {
    return Dot(fx, fy) < face_cos || Dot(Normalize(x0), Normalize(y0)) < kNormalCreaseCos ||
           Dot(Normalize(x1), Normalize(y1)) < kNormalCreaseCos;
}

std::vector<OutlineEdge> OutlineEdges(const stream::ChartTile& tile, uint64_t vertex_count) {
    struct E {
        uint32_t a, b, tri;
    };
    std::vector<E> all;
    all.reserve(tile.triangles.size() * 3);
    for (uint32_t t = 0; t < tile.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) {
            uint32_t a = tile.triangles[t][size_t(k)], b = tile.triangles[t][size_t((k + 1) % 3)];
            if (a > b)
                std::swap(a, b);
            all.push_back({a, b, t});
        }
    std::sort(all.begin(), all.end(), [](const E& x, const E& y) {
        return x.a != y.a ? x.a < y.a : x.b != y.b ? x.b < y.b : x.tri < y.tri;
    });
    std::vector<OutlineEdge> out;
    for (size_t i = 0; i < all.size();) {
        size_t j = i;
        while (j < all.size() && all[j].a == all[i].a && all[j].b == all[i].b)
            ++j;
        const E e = all[i];
        const bool outline = j - i == 1;
        i = j;
        if (!outline || e.a == e.b)
            continue;
        const uint64_t ga = tile.vertex_id[e.a], gb = tile.vertex_id[e.b];
        if (ga >= vertex_count || gb >= vertex_count || ga == gb)
            continue;
        OutlineEdge o;
        if (ga < gb)
            o = {ga, gb, e.a, e.b, e.tri};
        else
            o = {gb, ga, e.b, e.a, e.tri};
        out.push_back(o);
    }
    std::sort(out.begin(), out.end(), [](const OutlineEdge& x, const OutlineEdge& y) {
        return x.g0 != y.g0 ? x.g0 < y.g0 : x.g1 < y.g1;
    });
    return out;
}

Vec3f FaceNormal(const stream::ChartTile& tile, uint32_t triangle) {
    const auto& f = tile.triangles[triangle];
    return Normalize(Cross(tile.position[f[1]] - tile.position[f[0]],
                           tile.position[f[2]] - tile.position[f[0]]));
}

struct SeamStitcher::Parts {
    std::vector<SeamEdge> edges;
    std::vector<float> targets;
    std::vector<std::pair<uint32_t, Vec3f>> normals;
};

ChartNeighbours FindChartNeighbours(const BakeView& view) {
    // Charts that share a vertex have touching boxes (each box holds its chart's vertices;
    // the margin only adds candidates, which find no common key).
    const auto& ch = view.manifest.charts;
    const double margin = 1e-5 * Length(view.manifest.bbox_max - view.manifest.bbox_min);
    auto touch = [&](size_t a, size_t b) {
        for (int k = 0; k < 3; ++k)
            if (double(ch[a].bbox_min[k]) > double(ch[b].bbox_max[k]) + margin ||
                double(ch[b].bbox_min[k]) > double(ch[a].bbox_max[k]) + margin)
                return false;
        return true;
    };
    ChartNeighbours n;
    n.start.assign(1, 0);
    for (size_t a = 0; a < ch.size(); ++a) {
        for (size_t b = 0; b < ch.size(); ++b)
            if (b != a && touch(a, b))
                n.list.push_back(uint32_t(b));
        n.start.push_back(uint32_t(n.list.size()));
    }
    return n;
}

std::vector<uint32_t> LastNeighbours(const BakeView& view) {
    const ChartNeighbours n = FindChartNeighbours(view);
    std::vector<uint32_t> last(view.chart_count());
    for (uint32_t a = 0; a < last.size(); ++a)
        last[a] = n.start[a] == n.start[a + 1] ? a : std::max(a, n.list[n.start[a + 1] - 1]);
    return last;
}

SeamStitcher::SeamStitcher(const BakeView& view, size_t cache_bytes, const std::string& temp_dir)
    : cache_bytes_(cache_bytes),
      fd_(OpenTemporaryFile(temp_dir, "stitch data")),
      stored_(view.chart_count(), {0, 0}) {
    ChartNeighbours n = FindChartNeighbours(view);
    neighbour_start_ = std::move(n.start);
    neighbours_ = std::move(n.list);
}

SeamStitcher::~SeamStitcher() {
    ::close(fd_);
}

namespace {

// The parts' arrays one after the other, behind their three counts.
template <typename T>
void Append(std::vector<char>& out, const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const size_t at = out.size();
    out.resize(at + v.size() * sizeof(T));
    if (!v.empty())
        std::memcpy(out.data() + at, v.data(), v.size() * sizeof(T));
}

template <typename T>
void Take(const std::vector<char>& in, size_t& at, uint64_t count, std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    CHECK_LE(at + count * sizeof(T), in.size());
    v.resize(count);
    if (count)
        std::memcpy(v.data(), in.data() + at, count * sizeof(T));
    at += count * sizeof(T);
}

}  // namespace

std::shared_ptr<const ChartSeams> SeamStitcher::Chart(const BakeView& view, uint32_t c) const {
    const int blocks = view.solution.radiosity ? 3 : 9;
    CHECK_LT(c, stored_.size());
    std::pair<uint64_t, uint64_t> at;
    {
        std::lock_guard lock(mutex_);
        at = stored_[c];
    }
    Parts parts;
    if (at.second > 0) {
        std::vector<char> bytes(at.second);
        for (size_t done = 0; done < bytes.size();) {
            const ssize_t r = ::pread(fd_, bytes.data() + done, bytes.size() - done,
                                      off_t(at.first + done));
            if (r <= 0)
                IoError({"stitch data (temporary file)", at.first + done}, "read failed: {}",
                        r < 0 ? ErrnoString(errno) : "unexpected end");
            done += size_t(r);
        }
        uint64_t count[3];
        std::memcpy(count, bytes.data(), sizeof(count));
        size_t pos = sizeof(count);
        Take(bytes, pos, count[0], parts.edges);
        Take(bytes, pos, count[1], parts.targets);
        std::vector<uint32_t> vertex;
        std::vector<Vec3f> normal;
        Take(bytes, pos, count[2], vertex);
        Take(bytes, pos, count[2], normal);
        for (size_t k = 0; k < vertex.size(); ++k)
            parts.normals.push_back({vertex[k], normal[k]});
    } else {
        parts = BuildParts(view, c, nullptr);
        const uint64_t count[3] = {parts.edges.size(), parts.targets.size(),
                                   parts.normals.size()};
        std::vector<char> bytes(sizeof(count));
        std::memcpy(bytes.data(), count, sizeof(count));
        Append(bytes, parts.edges);
        Append(bytes, parts.targets);
        std::vector<uint32_t> vertex;
        std::vector<Vec3f> normal;
        for (const auto& [v, n] : parts.normals) {
            vertex.push_back(v);
            normal.push_back(n);
        }
        Append(bytes, vertex);
        Append(bytes, normal);
        uint64_t off;
        {
            std::lock_guard lock(mutex_);
            off = file_end_;
            file_end_ += bytes.size();
        }
        for (size_t done = 0; done < bytes.size();) {
            const ssize_t w = ::pwrite(fd_, bytes.data() + done, bytes.size() - done,
                                       off_t(off + done));
            if (w <= 0)
                IoError({"stitch data (temporary file)", off + done}, "write failed: {}",
                        w < 0 ? ErrnoString(errno) : "no space");
            done += size_t(w);
        }
        std::lock_guard lock(mutex_);
        if (stored_[c].second == 0)
            stored_[c] = {off, bytes.size()};
    }
    if (parts.edges.empty())
        return std::make_shared<const ChartSeams>();
    return std::make_shared<const ChartSeams>(blocks, std::move(parts.edges),
                                              std::move(parts.targets), std::move(parts.normals));
}

ChartSeams SeamStitcher::Build(const BakeView& view, uint32_t c, SeamGraphStats* stats) const {
    Parts parts = BuildParts(view, c, stats);
    if (parts.edges.empty())
        return {};
    return ChartSeams(view.solution.radiosity ? 3 : 9, std::move(parts.edges),
                      std::move(parts.targets), std::move(parts.normals));
}

uint64_t SeamStitcher::hits() const {
    std::lock_guard lock(mutex_);
    return hits_;
}

uint64_t SeamStitcher::misses() const {
    std::lock_guard lock(mutex_);
    return misses_;
}

std::shared_ptr<const SeamStitcher::Sides> SeamStitcher::SidesOf(const BakeView& view,
                                                                  uint32_t c) const {
    {
        std::lock_guard lock(mutex_);
        auto it = cached_.find(c);
        if (it != cached_.end()) {
            lru_.splice(lru_.begin(), lru_, it->second.at);
            ++hits_;
            return it->second.sides;
        }
        ++misses_;
    }
    const int blocks = view.solution.radiosity ? 3 : 9;
    const stream::ChartTile tile = stream::ReadTile(view.TilePath(c), stream::TileParts::Mesh);
    auto sides = std::make_shared<const Sides>(SampleSides(view, c, tile, blocks));
    std::lock_guard lock(mutex_);
    if (sides->bytes <= cache_bytes_ && !cached_.count(c)) {
        lru_.push_front(c);
        cached_[c] = {sides, lru_.begin()};
        cached_bytes_ += sides->bytes;
        while (cached_bytes_ > cache_bytes_) {
            auto old = cached_.find(lru_.back());
            cached_bytes_ -= old->second.sides->bytes;
            cached_.erase(old);
            lru_.pop_back();
        }
    }
    return sides;
}

SeamStitcher::Parts SeamStitcher::BuildParts(const BakeView& view, uint32_t c,
                                              SeamGraphStats* stats) const {
    const int blocks = view.solution.radiosity ? 3 : 9;
    CHECK_LT(c, view.chart_count());
    // The neighbourhood in chart order: every chart with a vertex of c.
    std::vector<uint32_t> charts(neighbours_.begin() + neighbour_start_[c],
                                 neighbours_.begin() + neighbour_start_[c + 1]);
    charts.insert(std::lower_bound(charts.begin(), charts.end(), c), c);
    const uint32_t self = uint32_t(std::lower_bound(charts.begin(), charts.end(), c) - charts.begin());
    std::vector<std::shared_ptr<const Sides>> sides(charts.size());
    sides[self] = SidesOf(view, c);
    if (sides[self]->keys.empty())
        return {};
    for (size_t k = 0; k < charts.size(); ++k)
        if (k != self)
            sides[k] = SidesOf(view, charts[k]);
    auto side = [&](At a) -> const Side& { return sides[a.slot]->sides[a.index]; };
    auto key = [&](At a) -> const Key& { return sides[a.slot]->keys[a.index]; };

    // The keys with a vertex of c's outline: every chart holding one is in the
    // neighbourhood, so their pairing below is the whole pass's.
    std::vector<uint64_t> outline;
    for (const Key& k : sides[self]->keys) {
        outline.push_back(k.first);
        outline.push_back(k.second);
    }
    std::sort(outline.begin(), outline.end());
    outline.erase(std::unique(outline.begin(), outline.end()), outline.end());
    auto on_outline = [&](uint64_t g) {
        return std::binary_search(outline.begin(), outline.end(), g);
    };
    std::vector<At> met;  // in the pass's order, then grouped by key (stable)
    for (uint32_t k = 0; k < charts.size(); ++k)
        for (uint32_t i = 0; i < sides[k]->keys.size(); ++i)
            if (on_outline(sides[k]->keys[i].first) || on_outline(sides[k]->keys[i].second))
                met.push_back({k, i});
    std::stable_sort(met.begin(), met.end(), [&](At a, At b) { return key(a) < key(b); });

    // The pass's pairing, key by key: a side waits until a side of another chart meets it.
    SeamGraphStats st;
    std::vector<Pair> pairs;
    for (size_t i = 0; i < met.size();) {
        size_t j = i;
        const At* waiting = nullptr;
        for (; j < met.size() && key(met[j]) == key(met[i]); ++j) {
            if (!waiting) {
                waiting = &met[j];
                continue;
            }
            if (waiting->slot == met[j].slot)
                continue;  // a split vertex inside one chart
            const Side &x = side(*waiting), &y = side(met[j]);
            if (Crease(x.normal, y.normal, x.n0, y.n0, x.n1, y.n1, kStitchFoldCos)) {
                pairs.push_back({*waiting, met[j], true});
                if (met[j].slot == self)
                    ++st.fold_edges;
            } else if (x.intervals == y.intervals) {
                pairs.push_back({*waiting, met[j], false});
            }
            waiting = nullptr;
        }
        i = j;
    }
    std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
        return a.y.slot != b.y.slot ? a.y.slot < b.y.slot : a.y.index < b.y.index;
    });

    // c's edges in the order they are met, with the mean of both sides' samples (a crease:
    // c's own samples, no correction along it, so the corrections of stitched edges nearby
    // fade to zero there instead of reaching across it).
    std::vector<SeamEdge> edges;
    std::vector<float> targets;
    std::vector<End> ends;
    for (const Pair& p : pairs) {
        if (p.x.slot != self && p.y.slot != self)
            continue;
        if (p.y.slot == self && !p.crease)
            ++st.stitched_edges;
        const Side &x = side(p.x), &y = side(p.y), &s = p.x.slot == self ? x : y;
        SeamEdge e;
        e.a = s.a;
        e.b = s.b;
        e.band = s.band;
        e.first = uint32_t(targets.size() / size_t(blocks));
        e.count = s.intervals + 1;
        if (p.crease) {
            targets.insert(targets.end(), s.vals, s.vals + size_t(e.count) * size_t(blocks));
            edges.push_back(e);
            continue;
        }
        for (uint32_t k = 0; k <= s.intervals; ++k) {
            const float* vx = &x.vals[size_t(k) * size_t(blocks)];
            const float* vy = &y.vals[size_t(k) * size_t(blocks)];
            // Each side's brightness with its shading normal there (interpolated as shown).
            const float t = float(k) / float(s.intervals);
            const double wx = Weight(vx, Normalize(x.n0 * (1 - t) + x.n1 * t), blocks),
                         wy = Weight(vy, Normalize(y.n0 * (1 - t) + y.n1 * t), blocks);
            for (int b = 0; b < blocks; ++b)
                targets.push_back(float((wx * vx[b] + wy * vy[b]) / (wx + wy)));
        }
        edges.push_back(e);
        ends.push_back({key(p.y).first, s.v0, s.n0, e.first});
        ends.push_back({key(p.y).second, s.v1, s.n1, e.first + e.count - 1});
    }
    st.samples = targets.size() / size_t(blocks);
    if (stats)
        *stats = st;
    if (edges.empty())
        return {};

    // The ends take the mean over every chart whose stitched edges meet there.
    std::vector<uint64_t> end_vertices;
    for (const End& end : ends)
        end_vertices.push_back(end.g);
    std::sort(end_vertices.begin(), end_vertices.end());
    VertexSums vs;
    for (const Pair& p : pairs) {
        if (p.crease)
            continue;
        for (const At a : {p.x, p.y})
            for (const bool last : {false, true}) {
                const uint64_t g = last ? key(a).second : key(a).first;
                if (std::binary_search(end_vertices.begin(), end_vertices.end(), g))
                    vs.Add(g, side(a), last, blocks);
            }
    }
    std::vector<std::pair<uint32_t, Vec3f>> normals;
    for (const End& end : ends) {
        const VertexSum& sum = vs.sum.at(end.g);
        for (int b = 0; b < blocks; ++b)
            targets[size_t(end.target) * size_t(blocks) + size_t(b)] =
                float(sum.e[size_t(b)] / sum.weight);
        // One shading normal on both sides too, unless the copies disagree as at a
        // crease (ingest keeps each side's own normal there).
        const Vec3f shared(Normalize(sum.normal));
        if (Dot(shared, Normalize(end.normal)) >= kNormalCreaseCos)
            normals.push_back({end.v, shared});
    }
    std::sort(normals.begin(), normals.end(),
              [](const auto& x, const auto& y) { return x.first < y.first; });
    normals.erase(std::unique(normals.begin(), normals.end(),
                              [](const auto& x, const auto& y) { return x.first == y.first; }),
                  normals.end());
    return {std::move(edges), std::move(targets), std::move(normals)};
}

std::vector<ChartSeams> BuildSeamStitch(const BakeView& view, SeamGraphStats* stats) {
    const SeamStitcher stitcher(view, size_t(16) << 20);
    std::vector<ChartSeams> out(view.chart_count());
    SeamGraphStats sum;
    for (uint32_t c = 0; c < out.size(); ++c) {
        SeamGraphStats st;
        out[c] = stitcher.Build(view, c, &st);
        sum.stitched_edges += st.stitched_edges;
        sum.fold_edges += st.fold_edges;
        sum.samples += st.samples;
    }
    if (stats)
        *stats = sum;
    return out;
}

}  // namespace mebake::output
