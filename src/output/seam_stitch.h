// One field across chart borders: each chart's shown field is corrected near the border
// edges it shares with another chart so that, at any point of such an edge, both charts show
// the same value (issue 14, item 3).
//
// Every chart has its own square and its own fitted field, so the two charts of a border edge
// give different E at the same surface point. seam_graph.h pairs the border edges and gives,
// for each, target values S(t) along it (the mean of both sides' E at samples t_k, the mean
// of every chart's E at the edge's vertices, linear in between): one value seen from both
// sides. The stitched field of a chart is
//   E*(x) = E(x) + fade(x) * sum_e w_e(x) c_e(x) / sum_e w_e(x),
//   c_e(x) = S_e(t_e) - E(p_e),  w_e = phi_e(d_e) / d_e^2,  fade = max_e phi_e(d_e),
// over the chart's border edges e within their band, with p_e the point of e nearest to x, t_e
// its parameter, d_e = |x - p_e| in chart coordinates and phi_e(d) = smoothstep(1 - d / b_e)
// falling to 0 at the band's width b_e (a few texels, tied to the leaf size at the edge).
// The inverse-distance weights make E* = S_e(t) exactly on an edge (from both sides) and
// keep E* continuous everywhere (Shepard interpolation of the border corrections); beyond
// every band the chart shows its own field. The shading normals of the edges' vertices are
// made one as well (the mean of their copies), blended in by the same fade, so B is one
// value from both sides and each chart's own normals hold beyond the band. Vector irradiance
// is a world-space quantity, so the mean of both sides' E is meaningful; B then follows with each
// side's shading normal.
#pragma once

#include "core/vec.h"
#include "output/continuous_field.h"

#include <cstdint>
#include <vector>

namespace mebake::output {

// A border edge in one chart's coordinates with its targets S at t = k / (count - 1),
// k = 0..count-1 (count >= 2), blocks floats each, from a to b.
struct SeamEdge {
    Vec2f a, b;
    float band = 0;      // width of the blend, chart coordinates
    uint32_t first = 0;  // index of the first target (in samples, not floats)
    uint32_t count = 0;
};

class ChartSeams {
public:
    ChartSeams() = default;
    // Builds the look-up grid over the unit square. `normals`: (tile vertex, shading normal)
    // for the ends of the edges, sorted by vertex: the mean of the copies in every chart
    // there, so the interpolated shading normal is one along the edge as well.
    ChartSeams(int blocks, std::vector<SeamEdge> edges, std::vector<float> targets,
               std::vector<std::pair<uint32_t, Vec3f>> normals = {});

    bool empty() const { return edges_.empty(); }
    size_t edge_count() const { return edges_.size(); }
    const std::vector<SeamEdge>& edges() const { return edges_; }
    const std::vector<std::pair<uint32_t, Vec3f>>& normals() const { return normals_; }
    // Target of edge e at t in [0, 1].
    void Target(const SeamEdge& e, double t, float* out) const;
    // val holds field's value at (u, v); adds the stitch correction to it.
    void Apply(const ContinuousField& field, double u, double v, float* val) const;
    // How much of the stitch holds at (u, v): 1 on a border edge, 0 beyond every band (the
    // `fade` above). The shared shading normals blend in with it, so that beyond the band
    // each chart shades with its own vertex normals, as the mesh (and the path tracer) does.
    double Fade(double u, double v) const;

private:
    // f(edge, t, pu, pv, d, phi) for every edge whose band holds (u, v): the nearest point
    // (pu, pv) of the edge at parameter t, at distance d, and the blend phi(d) there.
    template <typename F>
    void ForEdgesAt(double u, double v, F&& f) const;

    int blocks_ = 0;
    std::vector<SeamEdge> edges_;
    std::vector<float> targets_;
    std::vector<std::pair<uint32_t, Vec3f>> normals_;
    // Uniform grid of n x n cells; cell k lists the edges whose band reaches it.
    uint32_t n_ = 0;
    std::vector<uint32_t> cell_start_, cell_edges_;
};

}  // namespace mebake::output
