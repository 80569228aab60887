#include "output/seam_stitch.h"

#include "core/check.h"

#include <algorithm>
#include <cmath>

namespace mebake::output {

namespace {

constexpr uint32_t kMaxGrid = 256;

struct Box {
    double u0, v0, u1, v1;
};

Box EdgeBox(const SeamEdge& e) {
    return {std::min(e.a.x, e.b.x) - double(e.band), std::min(e.a.y, e.b.y) - double(e.band),
            std::max(e.a.x, e.b.x) + double(e.band), std::max(e.a.y, e.b.y) + double(e.band)};
}

uint32_t Cell(double x, uint32_t n) {
    return uint32_t(std::clamp(int64_t(std::floor(x * double(n))), int64_t(0), int64_t(n - 1)));
}

}  // namespace

ChartSeams::ChartSeams(int blocks, std::vector<SeamEdge> edges, std::vector<float> targets,
                       std::vector<std::pair<uint32_t, Vec3f>> normals)
    : blocks_(blocks),
      edges_(std::move(edges)),
      targets_(std::move(targets)),
      normals_(std::move(normals)) {
    CHECK(blocks_ >= 1 && blocks_ <= 9);
    if (edges_.empty())
        return;
    double widest = 0;
    for (const SeamEdge& e : edges_) {
        CHECK_GE(e.count, 2u);
        CHECK_LE(size_t(e.first + e.count) * size_t(blocks_), targets_.size());
        CHECK_GT(e.band, 0.f);
        widest = std::max(widest, double(e.band));
    }
    n_ = uint32_t(std::clamp(std::floor(1.0 / widest), 1.0, double(kMaxGrid)));
    // Counting sort of (cell, edge) pairs: each edge in every cell its band box meets.
    std::vector<uint32_t> count(size_t(n_) * n_ + 1, 0);
    auto for_cells = [&](const SeamEdge& e, auto&& f) {
        const Box b = EdgeBox(e);
        for (uint32_t j = Cell(b.v0, n_); j <= Cell(b.v1, n_); ++j)
            for (uint32_t i = Cell(b.u0, n_); i <= Cell(b.u1, n_); ++i)
                f(size_t(j) * n_ + i);
    };
    for (const SeamEdge& e : edges_)
        for_cells(e, [&](size_t k) { ++count[k + 1]; });
    for (size_t k = 1; k < count.size(); ++k)
        count[k] += count[k - 1];
    cell_start_ = count;
    cell_edges_.resize(count.back());
    for (uint32_t idx = 0; idx < edges_.size(); ++idx)
        for_cells(edges_[idx], [&](size_t k) { cell_edges_[count[k]++] = idx; });
}

void ChartSeams::Target(const SeamEdge& e, double t, float* out) const {
    const double x = std::clamp(t, 0.0, 1.0) * double(e.count - 1);
    const uint32_t k = std::min(uint32_t(x), e.count - 2);
    const float f = float(x - double(k));
    const float* s0 = &targets_[size_t(e.first + k) * size_t(blocks_)];
    const float* s1 = s0 + blocks_;
    for (int b = 0; b < blocks_; ++b)
        out[b] = s0[b] + f * (s1[b] - s0[b]);
}

template <typename F>
void ChartSeams::ForEdgesAt(double u, double v, F&& f) const {
    if (edges_.empty())
        return;
    u = std::clamp(u, 0.0, 1.0);
    v = std::clamp(v, 0.0, 1.0);
    const size_t cell = size_t(Cell(v, n_)) * n_ + Cell(u, n_);
    for (uint32_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
        const SeamEdge& e = edges_[cell_edges_[k]];
        const double ex = double(e.b.x) - e.a.x, ey = double(e.b.y) - e.a.y;
        const double len2 = ex * ex + ey * ey;
        double t = len2 > 0 ? ((u - e.a.x) * ex + (v - e.a.y) * ey) / len2 : 0;
        t = std::clamp(t, 0.0, 1.0);
        const double pu = e.a.x + t * ex, pv = e.a.y + t * ey;
        // Most edges of the cell are farther than their band: the squared distance says so
        // without hypot where it is past the band by more than rounding (1e-10 relative;
        // both are within a few ulps), so the same edges pass as by hypot alone.
        const double du = u - pu, dv = v - pv, band = double(e.band);
        if (du * du + dv * dv > band * band * (1 + 1e-10))
            continue;
        const double d = std::hypot(du, dv);
        if (d >= band)
            continue;
        const double s = 1 - d / band;
        f(e, t, pu, pv, d, s * s * (3 - 2 * s));
    }
}

void ChartSeams::Apply(const ContinuousField& field, double u, double v, float* val) const {
    double sum[9] = {}, weights = 0, fade = 0;
    float target[9], own[9];
    ForEdgesAt(u, v, [&](const SeamEdge& e, double t, double pu, double pv, double d, double phi) {
        fade = std::max(fade, phi);
        // On the edge itself the weight is finite but dwarfs every other edge's.
        const double w = phi / std::max(d * d, 1e-30);
        Target(e, t, target);
        field.Eval(pu, pv, own);
        for (int b = 0; b < blocks_; ++b)
            sum[b] += w * (double(target[b]) - double(own[b]));
        weights += w;
    });
    if (!(weights > 0))
        return;
    for (int b = 0; b < blocks_; ++b)
        val[b] = float(double(val[b]) + fade * sum[b] / weights);
}

double ChartSeams::Fade(double u, double v) const {
    double fade = 0;
    ForEdgesAt(u, v, [&](const SeamEdge&, double, double, double, double, double phi) {
        fade = std::max(fade, phi);
    });
    return fade;
}

}  // namespace mebake::output
