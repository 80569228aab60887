#include "output/node_seams.h"

#include "core/error.h"

#include <algorithm>
#include <optional>

namespace mebake::output {

namespace {

constexpr float kSide = 1e-6f;  // offset to either side of an edge, in chart coordinates

float Luminance(const Vec3f& b) {
    return 0.2126f * b.x + 0.7152f * b.y + 0.0722f * b.z;
}

struct ChartResult {
    uint64_t edges = 0;
    std::vector<std::pair<float, float>> pairs;  // luminance on either side
};

// Samples along an edge from (u0, v0) in direction (du, dv) of length len; `across` is the
// unit offset to the other side.
void SampleEdge(const ChartShader& shader, float u0, float v0, float du, float dv, Vec2f across,
                int samples, ChartResult* out) {
    bool any = false;
    for (int k = 0; k < samples; ++k) {
        const float t = (float(k) + 0.5f) / float(samples);
        const Vec2f p(u0 + du * t, v0 + dv * t);
        std::optional<ShadingPoint> inside = shader.AtUvInside(p);
        if (!inside)
            continue;  // the virtual part is never displayed
        ShadingPoint& sp = *inside;
        sp.uv = p - across * kSide;
        const float y1 = Luminance(shader.Radiosity(sp));
        sp.uv = p + across * kSide;
        const float y2 = Luminance(shader.Radiosity(sp));
        out->pairs.push_back({y1, y2});
        any = true;
    }
    out->edges += any;
}

ChartResult SampleChart(const BakeView& view, uint32_t c, const stream::ChartTile& tile,
                        int samples) {
    ChartResult r;
    const auto field = view.Field(c);
    const ChartShader shader(tile, *field, view.solution.radiosity, view.scene, view.TilePath(c),
                             view.Seams(c));
    for (const solve::QuadNode& n : field->nodes()) {
        if (!n.leaf())
            continue;
        const float s = float(n.size()), u = float(n.U(1)), v = float(n.V(1));
        if (u < 1)  // right edge
            SampleEdge(shader, u, float(n.V(0)), 0, s, Vec2f(1, 0), samples, &r);
        if (v < 1)  // top edge
            SampleEdge(shader, float(n.U(0)), v, s, 0, Vec2f(0, 1), samples, &r);
    }
    return r;
}

}  // namespace

NodeSeamStats MeasureNodeSeams(const BakeView& view, int samples) {
    if (samples < 1 || samples > 16)
        UsageError("node seam samples {}: expected 1 to 16", samples);
    NodeSeamStats st;
    JumpStats jumps;
    ForEachTile(
        view, AllCharts(view), stream::TileParts::Mesh,
        [&](uint32_t c, stream::ChartTile& tile) { return SampleChart(view, c, tile, samples); },
        [&](uint32_t, stream::ChartTile&, ChartResult& r) {
            st.edges += r.edges;
            for (const auto& [y1, y2] : r.pairs)
                jumps.Add(y1, y2);
        });
    st.display = jumps.Summary();
    return st;
}

}  // namespace mebake::output
