#include "output/seam_graph.h"

#include "core/check.h"
#include "output/bake_view.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

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
    std::vector<float> vals;  // (intervals + 1) x blocks
};

struct ChartSides {
    std::vector<Key> keys;
    std::vector<Side> sides;
};

ChartSides SampleSides(const BakeView& view, uint32_t c, const stream::ChartTile& tile,
                       int blocks) {
    ChartSides out;
    const auto field = view.Field(c);
    const double res = double(std::max<uint32_t>(1, tile.meta.resolution));
    const ContinuousField shown(*field, 1.0 / res);
    const double texel = view.manifest.texel_size;
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
        s.vals.resize(size_t(s.intervals + 1) * size_t(blocks));
        for (uint32_t k = 0; k <= s.intervals; ++k) {
            const double t = double(k) / double(s.intervals);
            shown.Eval(s.a.x + t * (s.b.x - s.a.x), s.a.y + t * (s.b.y - s.a.y),
                       &s.vals[size_t(k) * size_t(blocks)]);
        }
        out.keys.push_back({e.g0, e.g1});
        out.sides.push_back(std::move(s));
    }
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

// The stitched edges of every chart as they are found, ends filled in at the end.
struct Collected {
    std::vector<std::vector<SeamEdge>> edges;
    std::vector<std::vector<End>> ends;
    std::vector<std::vector<float>> targets;
    std::unordered_map<uint64_t, VertexSum> vertex;
    std::unordered_set<Key, KeyHash> counted;  // (vertex, chart) already in `vertex`
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

void AddVertex(Collected& col, uint64_t g, const Side& s, bool last, int blocks) {
    if (!col.counted.insert({g, s.chart}).second)
        return;
    VertexSum& sum = col.vertex[g];
    sum.e.resize(size_t(blocks), 0.0);
    const float* v = &s.vals[size_t(last ? s.intervals : 0) * size_t(blocks)];
    const double w = Weight(v, Normalize(last ? s.n1 : s.n0), blocks);
    for (int b = 0; b < blocks; ++b)
        sum.e[size_t(b)] += w * double(v[b]);
    sum.weight += w;
    sum.normal += Vec3d(last ? s.n1 : s.n0);
    ++sum.n;
}

// A crease edge of one side with the side's own samples as targets: no correction along
// it, so the corrections of stitched edges nearby fade to zero there instead of reaching
// across it.
void AddCrease(Collected& col, const Side& s, int blocks) {
    auto& targets = col.targets[s.chart];
    SeamEdge e;
    e.a = s.a;
    e.b = s.b;
    e.band = s.band;
    e.first = uint32_t(targets.size() / size_t(blocks));
    e.count = s.intervals + 1;
    targets.insert(targets.end(), s.vals.begin(), s.vals.end());
    col.edges[s.chart].push_back(e);
}

// Records the edge (g0, g1) for both sides with the mean of their samples as targets.
void AddPair(Collected& col, const Key& key, const Side& x, const Side& y, int blocks) {
    for (const Side* s : {&x, &y}) {
        auto& targets = col.targets[s->chart];
        SeamEdge e;
        e.a = s->a;
        e.b = s->b;
        e.band = s->band;
        e.first = uint32_t(targets.size() / size_t(blocks));
        e.count = s->intervals + 1;
        for (uint32_t k = 0; k <= s->intervals; ++k) {
            const float* vx = &x.vals[size_t(k) * size_t(blocks)];
            const float* vy = &y.vals[size_t(k) * size_t(blocks)];
            // Each side's brightness with its shading normal there (interpolated as shown).
            const float t = float(k) / float(s->intervals);
            const double wx = Weight(vx, Normalize(x.n0 * (1 - t) + x.n1 * t), blocks),
                         wy = Weight(vy, Normalize(y.n0 * (1 - t) + y.n1 * t), blocks);
            for (int b = 0; b < blocks; ++b)
                targets.push_back(float((wx * vx[b] + wy * vy[b]) / (wx + wy)));
        }
        col.edges[s->chart].push_back(e);
        col.ends[s->chart].push_back({key.first, s->v0, s->n0, e.first});
        col.ends[s->chart].push_back({key.second, s->v1, s->n1, e.first + e.count - 1});
        AddVertex(col, key.first, *s, false, blocks);
        AddVertex(col, key.second, *s, true, blocks);
    }
}

}  // namespace

// A scan's hard edge with a normal per side was stitched as one surface: nefertiti's crown
// showed 0.61 where the path tracer has 1.84 (bench/RESULTS.md, "Issue 14 (session 8)").
bool Crease(const Vec3f& fx, const Vec3f& fy, const Vec3f& x0, const Vec3f& y0, const Vec3f& x1,
            const Vec3f& y1) {
    return Dot(fx, fy) < kFoldCos || Dot(Normalize(x0), Normalize(y0)) < kFoldCos ||
           Dot(Normalize(x1), Normalize(y1)) < kFoldCos;
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

std::vector<ChartSeams> BuildSeamStitch(const BakeView& view, SeamGraphStats* stats) {
    const int blocks = view.solution.radiosity ? 3 : 9;
    const size_t charts = view.chart_count();
    Collected col;
    col.edges.resize(charts);
    col.ends.resize(charts);
    col.targets.resize(charts);
    SeamGraphStats st;
    std::unordered_map<Key, Side, KeyHash> waiting;
    ForEachTile(
        view, AllCharts(view), stream::TileParts::Mesh,
        [&](uint32_t c, stream::ChartTile& tile) { return SampleSides(view, c, tile, blocks); },
        [&](uint32_t c, stream::ChartTile&, ChartSides& cs) {
            for (size_t i = 0; i < cs.sides.size(); ++i) {
                auto it = waiting.find(cs.keys[i]);
                if (it == waiting.end()) {
                    waiting.emplace(cs.keys[i], std::move(cs.sides[i]));
                    continue;
                }
                const Side& other = it->second;
                if (other.chart == c)
                    continue;  // a split vertex inside one chart
                const Side& own = cs.sides[i];
                if (Crease(other.normal, own.normal, other.n0, own.n0, other.n1, own.n1)) {
                    AddCrease(col, other, blocks);
                    AddCrease(col, cs.sides[i], blocks);
                    ++st.fold_edges;
                } else if (other.intervals == cs.sides[i].intervals) {
                    AddPair(col, cs.keys[i], other, cs.sides[i], blocks);
                    ++st.stitched_edges;
                }
                waiting.erase(it);
            }
        });
    waiting.clear();
    std::vector<ChartSeams> out(charts);
    for (size_t c = 0; c < charts; ++c) {
        auto& targets = col.targets[c];
        std::vector<std::pair<uint32_t, Vec3f>> normals;
        for (const End& end : col.ends[c]) {
            const VertexSum& sum = col.vertex.at(end.g);
            for (int b = 0; b < blocks; ++b)
                targets[size_t(end.target) * size_t(blocks) + size_t(b)] =
                    float(sum.e[size_t(b)] / sum.weight);
            // One shading normal on both sides too, unless the copies disagree as at a
            // crease (ingest keeps each side's own normal there).
            const Vec3f shared(Normalize(sum.normal));
            if (Dot(shared, Normalize(end.normal)) >= kFoldCos)
                normals.push_back({end.v, shared});
        }
        std::sort(normals.begin(), normals.end(),
                  [](const auto& x, const auto& y) { return x.first < y.first; });
        normals.erase(std::unique(normals.begin(), normals.end(),
                                  [](const auto& x, const auto& y) { return x.first == y.first; }),
                      normals.end());
        st.samples += targets.size() / size_t(blocks);
        if (!col.edges[c].empty())
            out[c] =
                ChartSeams(blocks, std::move(col.edges[c]), std::move(targets), std::move(normals));
        col.ends[c] = {};
    }
    if (stats)
        *stats = st;
    return out;
}

}  // namespace mebake::output
