#include "output/seams.h"

#include "core/check.h"
#include "core/error.h"
#include "core/log.h"
#include "core/paged_file.h"
#include "output/seam_graph.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

namespace mebake::output {

namespace {

constexpr int kMaxSamples = 16;
constexpr size_t kSpillCache = size_t(1) << 20;  // per temporary file

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
    std::array<float, kMaxSamples> y;
    Vec3f normal, n0, n1;
};

// A compared sample: the jump, the level and the edge (index of its key).
struct Sample {
    float diff, level;
    uint32_t edge;
};
struct EdgeKey {
    uint64_t g0, g1;
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
    // The samples and the compared edges go to temporary files (read back three times
    // below), the waiting sides are dropped once no later chart can pair them: memory does
    // not grow with the border length.
    BorderPairing<Waiting> pairing(view);
    DiskArray<Sample> samples(PagedFile::Temporary{{}, "seam samples"}, kSpillCache);
    DiskArray<EdgeKey> compared(PagedFile::Temporary{{}, "seam edges"}, kSpillCache);
    double level = 0;
    size_t most_waiting = 0;
    JumpStats display;
    SeamStats st;
    ForEachTile(
        view, AllCharts(view), stream::TileParts::Mesh,
        [&](uint32_t c, stream::ChartTile& tile) {
            return SampleOutline(view, c, tile, opt.samples);
        },
        [&](uint32_t c, stream::ChartTile&, std::vector<EdgeSamples>& edges) {
            for (const EdgeSamples& e : edges) {
                pairing.Add(c, {e.g0, e.g1}, Waiting{e.y, e.normal, e.n0, e.n1},
                            [&](const Waiting& w, const Waiting& s) {
                                if (Crease(w.normal, s.normal, w.n0, s.n0, w.n1, s.n1)) {
                                    ++st.fold_edges;  // B jumps here on the surface itself
                                    return;           // (not stitched either)
                                }
                                const uint32_t edge = uint32_t(compared.size());
                                compared.Push({e.g0, e.g1});
                                for (size_t k = 0; k < ns; ++k) {
                                    const float y1 = w.y[k], y2 = s.y[k];
                                    samples.Push({std::abs(y1 - y2), 0.5f * (y1 + y2), edge});
                                    level += 0.5f * (y1 + y2);
                                    display.Add(y1, y2);
                                }
                            });
            }
            pairing.Done(c);
            most_waiting = std::max(most_waiting, pairing.waiting());
        });
    spdlog::debug("seams: at most {} border sides waiting for their other side", most_waiting);
    st.seam_edges = compared.size();
    st.open_edges = pairing.open();
    st.samples = samples.size();
    st.display = display.Summary();
    if (st.samples == 0)
        return st;
    st.mean_level = level / double(st.samples);
    const double floor = std::max(1e-3 * st.mean_level, 1e-30);
    auto for_each_relative = [&](auto&& f) {
        for (uint64_t i = 0; i < st.samples; ++i) {
            const Sample s = samples.Get(i);
            f(s.diff / std::max(double(s.level), floor), s);
        }
    };
    double sum = 0;
    for_each_relative([&](double rel, const Sample& s) {
        sum += rel;
        if (rel > st.max_relative) {
            st.max_relative = rel;
            const EdgeKey worst = compared.Get(s.edge);
            st.worst_v0 = worst.g0;
            st.worst_v1 = worst.g1;
        }
    });
    st.mean_relative = sum / double(st.samples);
    const uint64_t q = std::min(st.samples - 1, uint64_t(std::ceil(0.95 * double(st.samples))) - 1);
    st.p95_relative = NthSmallest(
        q, [&](auto&& f) { for_each_relative([&](double rel, const Sample&) { f(rel); }); });
    return st;
}

}  // namespace mebake::output
