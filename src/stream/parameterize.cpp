// Chart parameterization for the Meshed Master Element (see parameterize.h): disc check,
// LSCM with two far-apart boundary pins, ARAP refinement guarded against flips, unit-square
// placement, distortion metrics on the final float uv.
#include "stream/parameterize.h"

#include "core/check.h"
#include "stream/bff.h"
#include "stream/cotan_laplacian.h"
#include "stream/lscm.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <numeric>
#include <utility>

namespace mebake::stream {

const char* ParamStatusName(ParamStatus status) {
    switch (status) {
    case ParamStatus::kOk:
        return "ok";
    case ParamStatus::kEmpty:
        return "empty";
    case ParamStatus::kBadIndex:
        return "bad index";
    case ParamStatus::kNonFinite:
        return "non-finite position";
    case ParamStatus::kNonManifold:
        return "non-manifold";
    case ParamStatus::kNotDisc:
        return "not a disc";
    case ParamStatus::kDegenerate:
        return "degenerate";
    case ParamStatus::kSolverFailed:
        return "solver failed";
    case ParamStatus::kFlipped:
        return "flipped triangles";
    case ParamStatus::kOverlap:
        return "overlapping uv";
    case ParamStatus::kDistorted:
        return "distorted";
    }
    return "?";
}

namespace {

// The first i in [lo, hi] where `holds` is true, or hi + 1, for a predicate that is false
// and then true along i; `guess` is only where the search starts.
template <class Pred>
int FirstTrue(int lo, int hi, int guess, Pred holds) {
    int i = std::clamp(guess, lo, hi + 1);
    while (i > lo && holds(i - 1))
        --i;
    while (i <= hi && !holds(i))
        ++i;
    return i;
}

}  // namespace

// The fraction of the chart's points in uv covered more than once: centres of a res x res
// grid strictly inside more than one triangle. No flipped triangle does not make a map
// one-to-one: a large chart that wraps around (lucy's drapery) can flatten without flips
// onto itself, and the light map then holds two surfaces in one texel (bench/RESULTS.md,
// "Issue 13 (session 8)": one merged chart held 20 % of its texels twice, and lucy's error
// went from 4.6 % to 15 %).
//
// A centre is inside when its three edge functions are all > 0 or all < 0. Along a row
// each edge function, evaluated in float as below, is monotone in the column (x, x - p.x,
// the product by the edge's dy and the difference are each rounded monotonically), so the
// columns where one edge function is > 0 (or < 0) are a prefix or a suffix of the row:
// each row's inside centres of either sign are one interval, found from where the edge
// crosses the row and checked by the same float expression at its ends (the same texels
// as testing every centre of the bounding box, without testing them). The centres covered
// at least once and at least twice are two bit sets, an interval marked a word at a time.
double UvOverlapFraction(std::span<const std::array<uint32_t, 3>> triangles,
                         std::span<const Vec2f> uv, uint32_t res) {
    // Each row's centres as bits, 64 to a word.
    const size_t words = (size_t(res) + 63) / 64;
    std::vector<uint64_t> once(words * res, 0), twice(words * res, 0);
    const float r = float(res);
    std::vector<float> centre(res);  // a texel centre's coordinate, as the scan computed it
    for (uint32_t i = 0; i < res; ++i)
        centre[i] = (float(i) + 0.5f) / r;
    for (const auto& t : triangles) {
        const Vec2f a = uv[t[0]], b = uv[t[1]], c = uv[t[2]];
        const int i0 = std::max(0, int(std::floor(std::min({a.x, b.x, c.x}) * r - 0.5f)));
        const int i1 = std::min(int(res) - 1, int(std::ceil(std::max({a.x, b.x, c.x}) * r - 0.5f)));
        const int j0 = std::max(0, int(std::floor(std::min({a.y, b.y, c.y}) * r - 0.5f)));
        const int j1 = std::min(int(res) - 1, int(std::ceil(std::max({a.y, b.y, c.y}) * r - 0.5f)));
        struct Edge {
            Vec2f p;
            float dx, dy;
            double columns_per_along;  // for the first guess only
        };
        Edge edges[3];
        const Vec2f corner[3] = {a, b, c};
        for (int k = 0; k < 3; ++k) {
            const Vec2f p = corner[k], q = corner[(k + 1) % 3];
            edges[k] = {p, q.x - p.x, q.y - p.y, double(r) / double(q.y - p.y)};
        }
        for (int j = j0; j <= j1; ++j) {
            const float y = centre[size_t(j)];
            // Columns whose centres are inside with all edge functions > 0, and < 0.
            int pos_lo = i0, pos_hi = i1, neg_lo = i0, neg_hi = i1;
            for (int k = 0; k < 3 && (pos_lo <= pos_hi || neg_lo <= neg_hi); ++k) {
                const Edge& e = edges[k];
                const float along = e.dx * (y - e.p.y), dy = e.dy;
                // The edge function (q - p) x (centre - p) of column i's centre.
                const auto w = [&](int i) { return along - dy * (centre[size_t(i)] - e.p.x); };
                if (dy == 0) {  // the same value along the row
                    const float w0 = w(i0);
                    if (!(w0 > 0))
                        pos_hi = pos_lo - 1;
                    if (!(w0 < 0))
                        neg_hi = neg_lo - 1;
                    continue;
                }
                // The column where the edge crosses the row (a NaN starts at i0).
                const double cross = double(e.p.x) * r - 0.5 + double(along) * e.columns_per_along;
                const int guess = cross > i1 + 1 ? i1 + 1 : cross >= i0 ? int(cross) : i0;
                if (dy < 0) {  // w grows along the row
                    pos_lo = std::max(pos_lo, FirstTrue(i0, i1, guess, [&](int i) { return w(i) > 0; }));
                    neg_hi = std::min(neg_hi, FirstTrue(i0, i1, guess, [&](int i) { return !(w(i) < 0); }) - 1);
                } else {  // w falls along the row (or dy is a NaN: nothing is inside)
                    pos_hi = std::min(pos_hi, FirstTrue(i0, i1, guess, [&](int i) { return !(w(i) > 0); }) - 1);
                    neg_lo = std::max(neg_lo, FirstTrue(i0, i1, guess, [&](int i) { return w(i) < 0; }));
                }
            }
            const auto mark = [&](int lo, int hi) {
                for (int i = lo; i <= hi;) {
                    const int first = i % 64, end = std::min(hi, i - first + 63);
                    const uint64_t bits = (~uint64_t(0) >> (63 - (end - i))) << first;
                    const size_t w = size_t(j) * words + size_t(i / 64);
                    twice[w] |= once[w] & bits;
                    once[w] |= bits;
                    i = end + 1;
                }
            };
            mark(pos_lo, pos_hi);  // the two intervals are disjoint
            mark(neg_lo, neg_hi);
        }
    }
    size_t covered = 0, covered_twice = 0;
    for (size_t w = 0; w < once.size(); ++w) {
        covered += size_t(__builtin_popcountll(once[w]));
        covered_twice += size_t(__builtin_popcountll(twice[w]));
    }
    return covered ? double(covered_twice) / double(covered) : 0;
}

namespace {


constexpr uint32_t kNone = ~uint32_t(0);

DiscCheck Fail(ParamStatus status, std::string message) {
    DiscCheck c;
    c.status = status;
    c.message = std::move(message);
    return c;
}

uint32_t Find(std::vector<uint32_t>& parent, uint32_t v) {
    while (parent[v] != v) {
        parent[v] = parent[parent[v]];
        v = parent[v];
    }
    return v;
}

}  // namespace

DiscCheck CheckDisc(uint32_t vertex_count, std::span<const std::array<uint32_t, 3>> triangles) {
    const size_t tri_count = triangles.size();
    if (tri_count == 0)
        return Fail(ParamStatus::kEmpty, "no triangles");
    if (tri_count > (size_t(1) << 30))
        return Fail(ParamStatus::kBadIndex, "too many triangles for 32-bit half-edge ids");
    for (size_t t = 0; t < tri_count; ++t) {
        const auto& f = triangles[t];
        if (f[0] >= vertex_count || f[1] >= vertex_count || f[2] >= vertex_count)
            return Fail(ParamStatus::kBadIndex,
                        fmt::format("triangle {} names a vertex >= {}", t, vertex_count));
        if (f[0] == f[1] || f[1] == f[2] || f[2] == f[0])
            return Fail(ParamStatus::kBadIndex, fmt::format("triangle {} repeats a vertex", t));
    }

    // Half-edge h = 3t + k runs from triangles[t][k] to triangles[t][k+1]. Sorting the
    // directed edges finds twins; a repeated directed edge means > 2 triangles on an edge
    // or two neighbours with opposite orientation.
    const uint32_t half_count = uint32_t(3 * tri_count);
    auto from = [&](uint32_t h) {
        return triangles[h / 3][h % 3];
    };
    auto to = [&](uint32_t h) {
        return triangles[h / 3][(h % 3 + 1) % 3];
    };
    // Sorted by (from, to, h): a counting sort on `from` (stable, h ascending), then an
    // insertion sort of each vertex's few outgoing half-edges by `to`, which is kept beside
    // (out_to[i] = to(order[i])): the twin of h is the half-edge leaving to(h) for from(h).
    std::vector<uint32_t> order(half_count), out_to(half_count);
    std::vector<uint32_t> out_start(size_t(vertex_count) + 1, 0);
    {
        for (uint32_t h = 0; h < half_count; ++h)
            ++out_start[from(h) + 1];
        for (uint32_t v = 0; v < vertex_count; ++v)
            out_start[v + 1] += out_start[v];
        std::vector<uint32_t> fill(out_start.begin(), out_start.end() - 1);
        for (uint32_t h = 0; h < half_count; ++h) {
            const uint32_t i = fill[from(h)]++;
            order[i] = h;
            out_to[i] = to(h);
        }
        for (uint32_t v = 0; v < vertex_count; ++v)
            for (uint32_t i = out_start[v] + 1; i < out_start[v + 1]; ++i)
                for (uint32_t j = i; j > out_start[v] && out_to[j - 1] > out_to[j]; --j) {
                    std::swap(order[j - 1], order[j]);
                    std::swap(out_to[j - 1], out_to[j]);
                }
    }
    // A repeated directed edge is a repeated `to` next to itself in its vertex's run.
    for (uint32_t v = 0; v < vertex_count; ++v)
        for (uint32_t i = out_start[v] + 1; i < out_start[v + 1]; ++i)
            if (out_to[i] == out_to[i - 1])
                return Fail(ParamStatus::kNonManifold,
                            fmt::format("edge ({}, {}) is used twice in the same direction "
                                        "(non-manifold edge or inconsistent orientation)",
                                        v, out_to[i]));
    std::vector<uint32_t> twin(half_count, kNone);
    for (uint32_t h = 0; h < half_count; ++h) {
        const uint32_t v = to(h), back = from(h);
        for (uint32_t i = out_start[v]; i < out_start[v + 1]; ++i)
            if (out_to[i] == back) {  // at most one: no edge repeats
                twin[h] = order[i];
                break;
            }
    }

    // Corners per vertex (CSR), unreferenced vertices, connectivity.
    std::vector<uint32_t> corner_start(size_t(vertex_count) + 1, 0);
    for (const auto& f : triangles)
        for (uint32_t v : f)
            ++corner_start[v + 1];
    for (uint32_t v = 0; v < vertex_count; ++v) {
        if (corner_start[v + 1] == 0)
            return Fail(ParamStatus::kNotDisc, fmt::format("vertex {} is unreferenced", v));
        corner_start[v + 1] += corner_start[v];
    }
    std::vector<uint32_t> corners(half_count);
    {
        std::vector<uint32_t> fill(corner_start.begin(), corner_start.end() - 1);
        for (uint32_t h = 0; h < half_count; ++h)
            corners[fill[from(h)]++] = h;
    }
    std::vector<uint32_t> parent(vertex_count);
    std::iota(parent.begin(), parent.end(), 0u);
    for (const auto& f : triangles) {
        parent[Find(parent, f[1])] = Find(parent, f[0]);
        parent[Find(parent, f[2])] = Find(parent, f[0]);
    }
    const uint32_t root = Find(parent, 0);
    for (uint32_t v = 1; v < vertex_count; ++v)
        if (Find(parent, v) != root)
            return Fail(ParamStatus::kNotDisc, "the chart has several connected components");

    // Vertex manifoldness: the corners around each vertex form a single fan. The corner
    // whose outgoing half-edge is h continues across twin(h) to the corner whose
    // outgoing half-edge follows twin(h) in its triangle.
    auto next_in_tri = [](uint32_t h) {
        return h - h % 3 + (h % 3 + 1) % 3;
    };
    auto prev_in_tri = [](uint32_t h) {
        return h - h % 3 + (h % 3 + 2) % 3;
    };
    uint32_t boundary_half = kNone;
    uint32_t boundary_count = 0;
    for (uint32_t v = 0; v < vertex_count; ++v) {
        uint32_t start = corners[corner_start[v]];
        uint32_t open_fans = 0;
        for (uint32_t c = corner_start[v]; c < corner_start[v + 1]; ++c) {
            const uint32_t h = corners[c];        // outgoing from v
            if (twin[prev_in_tri(h)] == kNone) {  // incoming edge on the boundary
                ++open_fans;
                start = h;
            }
        }
        if (open_fans > 1)
            return Fail(ParamStatus::kNonManifold,
                        fmt::format("vertex {} joins {} boundary fans", v, open_fans));
        uint32_t visited = 1;
        for (uint32_t h = start;;) {
            if (twin[h] == kNone) {
                ++boundary_count;
                boundary_half = h;
                break;
            }
            h = next_in_tri(twin[h]);
            if (h == start)
                break;
            if (++visited > corner_start[v + 1] - corner_start[v])
                break;
        }
        if (visited != corner_start[v + 1] - corner_start[v])
            return Fail(ParamStatus::kNonManifold,
                        fmt::format("vertex {} is pinched (its triangles form several fans)", v));
    }
    if (boundary_count == 0)
        return Fail(ParamStatus::kNotDisc, "closed surface (no boundary)");

    // Boundary loops: each boundary vertex has one outgoing boundary half-edge.
    std::vector<uint32_t> boundary_out(vertex_count, kNone);
    for (uint32_t h = 0; h < half_count; ++h)
        if (twin[h] == kNone)
            boundary_out[from(h)] = h;
    DiscCheck result;
    for (uint32_t h = boundary_half;;) {
        result.boundary.push_back(from(h));
        h = boundary_out[to(h)];
        if (h == boundary_half)
            break;
        if (result.boundary.size() > boundary_count)
            break;  // cannot happen once manifold
    }
    if (result.boundary.size() != boundary_count)
        return Fail(ParamStatus::kNotDisc,
                    fmt::format("several boundary loops (one has {} of {} boundary edges)",
                                result.boundary.size(), boundary_count));
    const int64_t edges = (int64_t(half_count) + boundary_count) / 2;
    const int64_t euler = int64_t(vertex_count) - edges + int64_t(tri_count);
    if (euler != 1)
        return Fail(
            ParamStatus::kNotDisc,
            fmt::format("Euler characteristic {} (a disc has 1): the chart has handles", euler));
    return result;
}

void MeasureDistortion(std::span<const Vec3f> position,
                       std::span<const std::array<uint32_t, 3>> triangles,
                       std::span<const Vec2f> uv, ChartParam* out) {
    const size_t tri_count = triangles.size();
    std::vector<double> area_3d(tri_count), area_uv(tri_count);
    std::vector<FlatTriangle> flat(tri_count);
    double sum_3d = 0, sum_uv = 0;
    for (size_t t = 0; t < tri_count; ++t) {
        const auto& f = triangles[t];
        flat[t] =
            FlattenTriangle(Vec3d(position[f[0]]), Vec3d(position[f[1]]), Vec3d(position[f[2]]));
        const Vec3d p0(position[f[0]]);
        area_3d[t] = 0.5 * Length(Cross(Vec3d(position[f[1]]) - p0, Vec3d(position[f[2]]) - p0));
        const Vec2d q0(uv[f[0]].x, uv[f[0]].y), q1(uv[f[1]].x, uv[f[1]].y),
            q2(uv[f[2]].x, uv[f[2]].y);
        area_uv[t] = 0.5 * Cross(q1 - q0, q2 - q0);
        sum_3d += area_3d[t];
        sum_uv += area_uv[t];
    }
    ParamMetrics& m = out->metrics;
    m.area_3d = sum_3d;
    m.virtual_fraction = 1 - sum_uv;
    out->scale = sum_uv > 0 ? std::sqrt(sum_3d / sum_uv) : 0;
    const double s2 = out->scale * out->scale;
    out->area_ratio.assign(tri_count, 0.f);

    double misplaced = 0, conformal_sum = 0, conformal_weight = 0;
    m.jacobian_deviation_max = 0;
    m.conformal_max = 1;
    std::vector<std::pair<double, double>> weighted_dev;  // (|r - 1|, A_T)
    weighted_dev.reserve(tri_count);
    for (size_t t = 0; t < tri_count; ++t) {
        misplaced += std::abs(area_3d[t] - s2 * area_uv[t]);
        if (area_uv[t] > 0 && s2 > 0) {
            const double r = area_3d[t] / (s2 * area_uv[t]);
            out->area_ratio[t] = float(r);
            if (area_3d[t] > 0) {
                m.jacobian_deviation_max = std::max(m.jacobian_deviation_max, std::abs(r - 1));
                weighted_dev.emplace_back(std::abs(r - 1), area_3d[t]);
            }
        } else if (area_3d[t] > 0) {
            weighted_dev.emplace_back(1.0, area_3d[t]);
            m.jacobian_deviation_max = std::max(m.jacobian_deviation_max, 1.0);
        }
        // Singular values of the 2x2 Jacobian J = [[a, b], [c, d]] (flat frame -> uv).
        const FlatTriangle& ft = flat[t];
        if (ft.area == 0)
            continue;
        double a = 0, b = 0, c = 0, d = 0;
        for (int j = 0; j < 3; ++j) {
            const Vec2f& p = uv[triangles[t][j]];
            a += p.x * ft.grad[j].x;
            b += p.x * ft.grad[j].y;
            c += p.y * ft.grad[j].x;
            d += p.y * ft.grad[j].y;
        }
        const double q = std::hypot(0.5 * (a + d), 0.5 * (c - b));
        const double r = std::hypot(0.5 * (a - d), 0.5 * (c + b));
        const double sigma1 = q + r, sigma2 = std::abs(q - r);
        const double ratio = sigma2 > 0 ? sigma1 / sigma2 : 1e30;
        conformal_sum += ratio * ft.area;
        conformal_weight += ft.area;
        m.conformal_max = std::max(m.conformal_max, ratio);
    }
    m.jacobian_deviation_mean = sum_3d > 0 ? misplaced / sum_3d : 0;
    constexpr int kCells = 8;
    std::array<double, kCells * kCells> cell_3d{}, cell_uv{};
    for (size_t t = 0; t < tri_count; ++t) {
        const auto& f = triangles[t];
        const double cx = (double(uv[f[0]].x) + uv[f[1]].x + uv[f[2]].x) / 3;
        const double cy = (double(uv[f[0]].y) + uv[f[1]].y + uv[f[2]].y) / 3;
        const int ix = std::clamp(int(cx * kCells), 0, kCells - 1);
        const int iy = std::clamp(int(cy * kCells), 0, kCells - 1);
        cell_3d[iy * kCells + ix] += area_3d[t];
        cell_uv[iy * kCells + ix] += s2 * area_uv[t];
    }
    double coarse = 0;
    for (int c = 0; c < kCells * kCells; ++c)
        coarse += std::abs(cell_3d[c] - cell_uv[c]);
    m.jacobian_deviation_coarse = sum_3d > 0 ? coarse / sum_3d : 0;
    m.conformal_mean = conformal_weight > 0 ? conformal_sum / conformal_weight : 1;
    std::sort(weighted_dev.begin(), weighted_dev.end());
    m.jacobian_deviation_p95 = 0;
    double acc = 0;
    for (const auto& [dev, w] : weighted_dev) {
        acc += w;
        m.jacobian_deviation_p95 = dev;
        if (acc >= 0.95 * sum_3d)
            break;
    }
}

namespace {

// A far-apart pair of boundary vertices (double sweep in 3D, ties to the first).
std::pair<uint32_t, uint32_t> FarPair(const TriMesh& chart, std::span<const uint32_t> boundary) {
    auto farthest = [&](uint32_t from) {
        const Vec3d p(chart.position[from]);
        uint32_t best = boundary[0];
        double best_d = -1;
        for (uint32_t v : boundary) {
            const Vec3d e = Vec3d(chart.position[v]) - p;
            if (Dot(e, e) > best_d) {
                best_d = Dot(e, e);
                best = v;
            }
        }
        return best;
    };
    const uint32_t a = farthest(boundary[0]);
    return {a, farthest(a)};
}

// Initial flattening (BFF or LSCM, with LSCM as BFF's fallback) and refinement. On
// failure sets out->status and out->message.
bool Flatten(const TriMesh& chart, std::span<const FlatTriangle> flat,
             std::span<const uint32_t> boundary, const ParamOptions& options,
             std::vector<Vec2d>* uv, ChartParam* out) {
    const uint32_t vertex_count = uint32_t(chart.vertex_count());
    // Plain locals, not a structured binding: lambdas below capture them (clang 14).
    const auto pins = FarPair(chart, boundary);
    const uint32_t pin0 = pins.first, pin1 = pins.second;
    if (pin0 == pin1) {
        out->status = ParamStatus::kDegenerate;
        out->message = "all boundary vertices coincide";
        return false;
    }
    auto lscm = [&] {
        const double distance = Length(Vec3d(chart.position[pin1]) - Vec3d(chart.position[pin0]));
        return SolveLscm(flat, chart.triangles, vertex_count, pin0, pin1, distance, uv);
    };
    bool ok = false;
    if (options.init == ParamInit::kBff) {
        ok = FlattenBff(chart.position, flat, chart.triangles, boundary, uv);
        out->metrics.init = ok ? ParamInit::kBff : ParamInit::kLscm;
    }
    if (!ok) {
        out->metrics.init = ParamInit::kLscm;
        ok = lscm();
    }
    if (!ok) {
        out->status = ParamStatus::kSolverFailed;
        out->message = "the initial flattening failed";
        return false;
    }
    out->metrics.init_flipped = CountFlips(*uv, chart.triangles);
    if (!options.refine)
        return true;

    std::vector<char> fixed(vertex_count, 0);
    fixed[pin0] = 1;
    CotanLaplacian laplacian;
    if (!laplacian.Factorize(flat, chart.triangles, fixed)) {
        out->status = ParamStatus::kSolverFailed;
        out->message = "Laplacian factorization failed";
        return false;
    }
    ArapReport report =
        RefineArap(flat, chart.triangles, laplacian, pin0, options.refine_options, uv);
    uint32_t flips = CountFlips(*uv, chart.triangles);
    if (flips > 0 && out->metrics.init == ParamInit::kBff) {
        // BFF's harmonic interior can fold on bad triangles; LSCM rarely does.
        std::vector<Vec2d> bff_uv;
        bff_uv.swap(*uv);
        if (lscm()) {
            const uint32_t lscm_flips = CountFlips(*uv, chart.triangles);
            const ArapReport second =
                RefineArap(flat, chart.triangles, laplacian, pin0, options.refine_options, uv);
            const uint32_t second_flips = CountFlips(*uv, chart.triangles);
            if (second_flips < flips) {
                out->metrics.init = ParamInit::kLscm;
                out->metrics.init_flipped = lscm_flips;
                report = second;
                flips = second_flips;
            } else {
                uv->swap(bff_uv);
            }
        } else {
            uv->swap(bff_uv);
        }
    }
    out->metrics.refine_iterations = report.iterations;
    out->metrics.refine_stopped_by_flip = report.stopped_by_flip;
    return true;
}

}  // namespace

ChartParam ParameterizeChart(const TriMesh& chart, const ParamOptions& options) {
    ChartParam out = FlattenChart(chart, options);
    if (out.status == ParamStatus::kOk)
        ClassifyChart(chart, options, &out);
    return out;
}

ChartParam FlattenChart(const TriMesh& chart, const ParamOptions& options) {
    ChartParam out;
    const uint32_t vertex_count = uint32_t(chart.vertex_count());
    if (chart.vertex_count() > kNone) {
        out.status = ParamStatus::kBadIndex;
        out.message = "too many vertices for 32-bit indices";
        return out;
    }
    for (uint32_t v = 0; v < vertex_count; ++v) {
        const Vec3f& p = chart.position[v];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
            out.status = ParamStatus::kNonFinite;
            out.message = fmt::format("vertex {} has a non-finite position", v);
            return out;
        }
    }
    DiscCheck disc = CheckDisc(vertex_count, chart.triangles);
    if (disc.status != ParamStatus::kOk) {
        out.status = disc.status;
        out.message = std::move(disc.message);
        return out;
    }

    const std::vector<FlatTriangle> flat = FlattenTriangles(chart.position, chart.triangles);
    double total_area = 0;
    for (const FlatTriangle& ft : flat)
        total_area += ft.area;
    if (!(total_area > 0)) {
        out.status = ParamStatus::kDegenerate;
        out.message = "all triangles are degenerate";
        return out;
    }

    std::vector<Vec2d> uv;
    if (!Flatten(chart, flat, disc.boundary, options, &uv, &out))
        return out;

    const SquareFit fit = FitUnitSquare(uv, options.margin, options.objective);
    out.uv.resize(vertex_count);
    for (uint32_t v = 0; v < vertex_count; ++v) {
        const Vec2d q = fit.Apply(uv[v]);
        out.uv[v] = Vec2f(std::clamp(float(q.x), 0.f, 1.f), std::clamp(float(q.y), 0.f, 1.f));
    }
    MeasureDistortion(chart.position, chart.triangles, out.uv, &out);
    std::vector<Vec2d> final_uv(vertex_count);
    for (uint32_t v = 0; v < vertex_count; ++v)
        final_uv[v] = Vec2d(out.uv[v].x, out.uv[v].y);
    out.metrics.flipped = CountFlips(final_uv, chart.triangles);
    out.status = ParamStatus::kOk;
    return out;
}

void ClassifyChart(const TriMesh& chart, const ParamOptions& options, ChartParam* param) {
    CHECK(param->status == ParamStatus::kOk);
    ChartParam& out = *param;
    if (out.metrics.flipped > 0) {
        out.status = ParamStatus::kFlipped;
        out.message = fmt::format("{} flipped uv triangles", out.metrics.flipped);
    } else if (const double overlap =
                   UvOverlapFraction(chart.triangles, out.uv, kOverlapResolution);
               overlap > kMaxOverlap) {
        out.status = ParamStatus::kOverlap;
        out.message = fmt::format("{:.1f} % of the uv map covered twice", 100 * overlap);
    } else if (out.metrics.jacobian_deviation_coarse > options.max_jacobian_deviation) {
        out.status = ParamStatus::kDistorted;
        out.message =
            fmt::format("coarse Jacobian deviation {:.4f} > {:.4f}",
                        out.metrics.jacobian_deviation_coarse, options.max_jacobian_deviation);
    }
}

}  // namespace mebake::stream
