#include "output/seams.h"

#include "core/check.h"
#include "core/error.h"
#include "output/seam_graph.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

namespace mebake::output {

namespace {

constexpr int kMaxSamples = 16;

float Luminance(const Vec3f& b) {
    return 0.2126f * b.x + 0.7152f * b.y + 0.0722f * b.z;
}

struct EdgeSamples {
    uint64_t g0 = 0, g1 = 0;             // g0 < g1
    std::array<float, kMaxSamples> y{};  // luminance at the samples, from g0 to g1
    Vec3f normal{};                      // the face beside the edge (unit)
    Vec3f n0{}, n1{};                    // the chart's shading normals at g0 and g1
};

struct Waiting {
    uint32_t chart;
    std::array<float, kMaxSamples> y;
    Vec3f normal, n0, n1;
};

// The outline edges of a tile (seam_graph.h) with B sampled along them.
std::vector<EdgeSamples> SampleOutline(const BakeView& view, uint32_t c,
                                       const stream::ChartTile& tile, int samples) {
    const auto field = view.Field(c);
    ChartShader shader(tile, *field, view.solution.radiosity, view.scene, view.TilePath(c),
                       view.Seams(c));
    std::vector<EdgeSamples> out;
    for (const OutlineEdge& e : OutlineEdges(tile, view.manifest.vertex_count)) {
        const auto& tri = tile.triangles[e.triangle];
        const int i0 = int(std::find(tri.begin(), tri.end(), e.v0) - tri.begin());
        const int i1 = int(std::find(tri.begin(), tri.end(), e.v1) - tri.begin());
        CHECK(i0 < 3 && i1 < 3);
        EdgeSamples s;
        s.g0 = e.g0;
        s.g1 = e.g1;
        s.normal = FaceNormal(tile, e.triangle);
        s.n0 = tile.normal[e.v0];
        s.n1 = tile.normal[e.v1];
        for (int k = 0; k < samples; ++k) {
            const float t = (float(k) + 0.5f) / float(samples);
            float b[3] = {0, 0, 0};
            b[i0] = 1 - t;
            b[i1] = t;
            s.y[size_t(k)] =
                Luminance(shader.Radiosity(shader.AtTriangle(e.triangle, b[0], b[1], b[2])));
        }
        out.push_back(s);
    }
    return out;
}

}  // namespace

SeamStats MeasureSeams(const BakeView& view, const SeamOptions& opt) {
    if (opt.samples < 1 || opt.samples > kMaxSamples)
        UsageError("seam samples {}: expected 1 to {}", opt.samples, kMaxSamples);
    const size_t ns = size_t(opt.samples);
    std::unordered_map<IdPair, Waiting, IdPairHash> waiting;
    struct Sample {
        float diff, level;
        uint32_t edge;
    };
    std::vector<Sample> samples;
    std::vector<std::pair<uint64_t, uint64_t>> compared;
    JumpStats display;
    SeamStats st;
    ForEachTile(
        view, AllCharts(view), stream::TileParts::Mesh,
        [&](uint32_t c, stream::ChartTile& tile) {
            return SampleOutline(view, c, tile, opt.samples);
        },
        [&](uint32_t c, stream::ChartTile&, std::vector<EdgeSamples>& edges) {
            for (const EdgeSamples& e : edges) {
                const auto key = std::make_pair(e.g0, e.g1);
                auto it = waiting.find(key);
                if (it == waiting.end()) {
                    waiting.emplace(key, Waiting{c, e.y, e.normal, e.n0, e.n1});
                    continue;
                }
                if (it->second.chart == c)
                    continue;  // a split vertex inside one chart
                const Waiting& w = it->second;
                if (Crease(w.normal, e.normal, w.n0, e.n0, w.n1, e.n1)) {
                    ++st.fold_edges;  // B jumps here on the surface itself (not stitched either)
                    waiting.erase(it);
                    continue;
                }
                const uint32_t edge = uint32_t(compared.size());
                compared.push_back(key);
                for (size_t k = 0; k < ns; ++k) {
                    const float y1 = it->second.y[k], y2 = e.y[k];
                    samples.push_back({std::abs(y1 - y2), 0.5f * (y1 + y2), edge});
                    display.Add(y1, y2);
                }
                waiting.erase(it);
            }
        });
    st.seam_edges = compared.size();
    st.open_edges = waiting.size();
    st.samples = samples.size();
    st.display = display.Summary();
    if (samples.empty())
        return st;
    double level = 0;
    for (const Sample& s : samples)
        level += s.level;
    st.mean_level = level / double(samples.size());
    const double floor = std::max(1e-3 * st.mean_level, 1e-30);
    std::vector<double> rel(samples.size());
    double sum = 0;
    for (size_t i = 0; i < samples.size(); ++i) {
        rel[i] = samples[i].diff / std::max(double(samples[i].level), floor);
        sum += rel[i];
        if (rel[i] > st.max_relative) {
            st.max_relative = rel[i];
            st.worst_v0 = compared[samples[i].edge].first;
            st.worst_v1 = compared[samples[i].edge].second;
        }
    }
    st.mean_relative = sum / double(samples.size());
    const size_t q =
        std::min(samples.size() - 1, size_t(std::ceil(0.95 * double(samples.size()))) - 1);
    std::nth_element(rel.begin(), rel.begin() + ptrdiff_t(q), rel.end());
    st.p95_relative = rel[q];
    return st;
}

}  // namespace mebake::output
