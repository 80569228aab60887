// Greedy merging of neighbouring charts (chart_merge.h).
//
// Rounds: the borders between charts are measured (length, and how much of it is fold);
// candidate pairs are ordered by the share of the smaller chart's perimeter they have in
// common, times the agreement of the two mean normals (charts that already look like one
// piece first); a matching is taken greedily in that order (each chart in at most one pair
// per round); every pair's union is parameterized, in parallel, and the unions that pass
// replace their two charts (the union keeps the smaller id). A pair is tried once: when a
// union fails, the pair is not tried again even after one side has grown (retrying made
// more work and, measured on lucy, more charts in the end, 34 against 21: a failed pair
// blocks its charts for a round, and the retries kept taking the best partners). Each
// pair of ids is parameterized at most once, which bounds the work. Rounds stop when no
// pair is left to try.
#include "stream/chart_merge.h"

#include "core/check.h"
#include "core/parallel.h"
#include "stream/geometry_image.h"
#include "stream/topology.h"
#include "stream/work_order.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

namespace mebake::stream {
namespace {

using Tri = std::array<uint32_t, 3>;
constexpr double kPi = 3.14159265358979323846;

struct Border {
    uint32_t a = 0, b = 0;  // a < b
    double length = 0;
    double fold = 0;  // length of the edges where the faces fold by more than fold_deg
    double score = 0;
};

struct Geometry {
    std::vector<Vec3d> normal;  // per face, unit (raw: folds are read before any smoothing)
    std::vector<double> area;
    std::vector<uint32_t> twin;
    std::vector<double> length;  // per half-edge: Borders reads it every round
};

Geometry Measure(const TriMesh& mesh) {
    Geometry g;
    const size_t nf = mesh.triangle_count();
    g.normal.resize(nf);
    g.area.resize(nf);
    for (size_t f = 0; f < nf; ++f) {
        const Tri& t = mesh.triangles[f];
        const Vec3d a(mesh.position[t[0]]), b(mesh.position[t[1]]), c(mesh.position[t[2]]);
        const Vec3d n = Cross(b - a, c - a);
        g.area[f] = 0.5 * Length(n);
        g.normal[f] = Normalize(n);
    }
    g.twin = BuildTwins(mesh.triangles, BuildEdgeGroups(mesh.triangles));
    g.length.resize(3 * nf);
    for (size_t h = 0; h < 3 * nf; ++h) {
        const Tri& tri = mesh.triangles[h / 3];
        g.length[h] =
            Length(Vec3d(mesh.position[tri[(h + 1) % 3]]) - Vec3d(mesh.position[tri[h % 3]]));
    }
    return g;
}

// Every border between two charts, scored, best first (ties by ids).
std::vector<Border> Borders(const Geometry& g, const std::vector<uint32_t>& chart,
                            size_t chart_count, double fold_cos) {
    std::vector<Border> edges;
    std::vector<double> perimeter(chart_count, 0);
    std::vector<Vec3d> normal(chart_count);
    std::vector<double> area(chart_count, 0);
    for (size_t f = 0; f < chart.size(); ++f) {
        normal[chart[f]] += g.normal[f] * g.area[f];
        area[chart[f]] += g.area[f];
    }
    for (uint32_t h = 0; h < 3 * chart.size(); ++h) {
        const uint32_t f = h / 3, t = g.twin[h];
        const double len = g.length[h];
        if (t == kNoIndex || chart[t / 3] != chart[f]) {
            perimeter[chart[f]] += len;
        }
        if (t == kNoIndex || t < h || chart[t / 3] == chart[f])
            continue;
        Border e;
        e.a = std::min(chart[f], chart[t / 3]);
        e.b = std::max(chart[f], chart[t / 3]);
        e.length = len;
        e.fold = Dot(g.normal[f], g.normal[t / 3]) < fold_cos ? len : 0;
        edges.push_back(e);
    }
    std::sort(edges.begin(), edges.end(), [](const Border& x, const Border& y) {
        return x.a != y.a ? x.a < y.a : x.b < y.b;
    });
    std::vector<Border> merged;
    for (const Border& e : edges) {
        if (!merged.empty() && merged.back().a == e.a && merged.back().b == e.b) {
            merged.back().length += e.length;
            merged.back().fold += e.fold;
        } else {
            merged.push_back(e);
        }
    }
    for (Border& e : merged) {
        const double shared = e.length / std::max(std::min(perimeter[e.a], perimeter[e.b]), 1e-300);
        const double agree = 0.5 * (1 + Dot(Normalize(normal[e.a]), Normalize(normal[e.b])));
        // Smaller unions first: charts then grow in balanced steps, about log2(charts)
        // rounds, rather than one neighbour per round around a chart that is already large.
        e.score = shared * agree / std::sqrt(std::max(area[e.a] + area[e.b], 1e-300));
    }
    std::sort(merged.begin(), merged.end(), [](const Border& x, const Border& y) {
        if (x.score != y.score)
            return x.score > y.score;
        return x.a != y.a ? x.a < y.a : x.b < y.b;
    });
    return merged;
}

// The union of two charts' faces as a mesh of its own (positions and triangles only: all
// the parameterization reads), vertices in increasing index order as ExtractCharts orders
// them, so that the chart builder's parameterization of an accepted union gives the same
// bits as the trial here. local_of is all kNoIndex on entry and on exit.
TriMesh Union(const TriMesh& mesh, const std::vector<uint32_t>& fa,
              const std::vector<uint32_t>& fb, std::vector<uint32_t>& local_of) {
    std::vector<uint32_t> faces(fa);
    faces.insert(faces.end(), fb.begin(), fb.end());
    std::sort(faces.begin(), faces.end());
    std::vector<uint32_t> used;
    for (uint32_t f : faces)
        for (uint32_t v : mesh.triangles[f])
            if (local_of[v] == kNoIndex) {
                local_of[v] = 0;
                used.push_back(v);
            }
    std::sort(used.begin(), used.end());
    TriMesh out;
    out.position.reserve(used.size());
    for (size_t i = 0; i < used.size(); ++i) {
        local_of[used[i]] = uint32_t(i);
        out.position.push_back(mesh.position[used[i]]);
    }
    out.triangles.reserve(faces.size());
    for (uint32_t f : faces) {
        const Tri& t = mesh.triangles[f];
        out.triangles.push_back({local_of[t[0]], local_of[t[1]], local_of[t[2]]});
    }
    for (uint32_t v : used)
        local_of[v] = kNoIndex;
    return out;
}

// A chart's parameterization, and the area of the square it needs (scale^2, in 3D
// units), or -1 when the chart fails the test.
struct Trial {
    ChartParam param;
    double square = -1;
};

// Face normals times twice the face area, averaged face -> vertex -> face a few times
// (as the segmentation does, segment.cpp): a scan's noise is not curvature.
std::vector<Vec3d> SmoothFaceNormals(const TriMesh& piece) {
    const size_t nf = piece.triangle_count();
    std::vector<Vec3d> face(nf), vertex(piece.vertex_count());
    std::vector<double> twice_area(nf);
    for (size_t f = 0; f < nf; ++f) {
        const Tri& t = piece.triangles[f];
        const Vec3d a(piece.position[t[0]]);
        face[f] = Cross(Vec3d(piece.position[t[1]]) - a, Vec3d(piece.position[t[2]]) - a);
        twice_area[f] = Length(face[f]);
    }
    for (int pass = 0; pass < 3; ++pass) {
        std::fill(vertex.begin(), vertex.end(), Vec3d());
        for (size_t f = 0; f < nf; ++f)
            for (uint32_t v : piece.triangles[f])
                vertex[v] += face[f];
        for (size_t f = 0; f < nf; ++f) {
            const Tri& t = piece.triangles[f];
            face[f] = Normalize(vertex[t[0]] + vertex[t[1]] + vertex[t[2]]) * twice_area[f];
        }
    }
    return face;
}

// How far the surface turns inside the cells of a grid over the chart's square (`cells`
// cells a side: 8, or the solver's horizon cells, MergeOptions::texel_size), in degrees: the
// 95 % area quantile of the angle between the mean normal of each cell of a finer grid and
// that of the coarse cell holding it. The solver takes a point's horizon (light below it
// does not count) from a level of the chart's geometry pyramid (solve/solver.cpp,
// HorizonNormal): on a chart that turns a lot inside one such cell the horizon tilts away
// from the surface and lit points go dark (the bunny's ear tip at 85 % error in one merged
// chart, while the horizon was 8 x 8 cells per chart). The finer grid has 4 x 4 cells per
// horizon cell, or fewer so that its cells hold about 4 triangles each: a scan's noise is
// not curvature, and where the horizon cells hold only a few triangles the horizon follows
// the surface anyway (spread 0).
double CellSpread(const TriMesh& piece, const std::vector<Vec2f>& uv, double fill, int cells) {
    constexpr double kPerCell = 4;  // triangles per fine cell
    int nf = 4 * cells;
    while (nf > cells && double(piece.triangle_count()) < kPerCell * nf * nf * fill)
        nf /= 2;
    if (nf <= cells)
        return 0;
    const int ratio = nf / cells;
    const std::vector<Vec3d> normal = SmoothFaceNormals(piece);
    std::vector<Vec3d> fine(size_t(nf * nf)), coarse(size_t(cells * cells));
    for (size_t f = 0; f < piece.triangle_count(); ++f) {
        const Tri& t = piece.triangles[f];
        const Vec3d n = normal[f];
        const double cx = (double(uv[t[0]].x) + uv[t[1]].x + uv[t[2]].x) / 3;
        const double cy = (double(uv[t[0]].y) + uv[t[1]].y + uv[t[2]].y) / 3;
        const int ix = std::clamp(int(cx * nf), 0, nf - 1);
        const int iy = std::clamp(int(cy * nf), 0, nf - 1);
        fine[size_t(iy * nf + ix)] += n;  // |n| = twice the area: area-weighted
        coarse[size_t((iy / ratio) * cells + ix / ratio)] += n;
    }
    std::vector<std::pair<double, double>> angle_area;
    double total = 0;
    for (int iy = 0; iy < nf; ++iy)
        for (int ix = 0; ix < nf; ++ix) {
            const Vec3d& f = fine[size_t(iy * nf + ix)];
            const Vec3d& c = coarse[size_t((iy / ratio) * cells + ix / ratio)];
            const double w = Length(f);
            if (!(w > 0) || !(Length(c) > 0))
                continue;
            const double cosine = std::clamp(Dot(Normalize(f), Normalize(c)), -1.0, 1.0);
            angle_area.emplace_back(std::acos(cosine) * 180 / kPi, w);
            total += w;
        }
    std::sort(angle_area.begin(), angle_area.end());
    double acc = 0;
    for (const auto& [angle, w] : angle_area) {
        acc += w;
        if (acc >= 0.95 * total)
            return angle;
    }
    return 0;
}

// Cells a side of the solver's horizon grid on a chart of this scale (geometry_image.h).
int HorizonCells(double scale, const MergeOptions& o) {
    if (!(o.texel_size > 0))
        return 8;
    return 1 << HorizonLevel(LevelOf(
                    ChartResolution(scale, o.texel_size, o.min_resolution, o.max_resolution)));
}

// `whole`: the flattening is wanted with its split tests even when the chart fails here
// (a chart on its own: the builder splits it by them). A union that fails the cheaper
// tests here is dropped, so its overlap test (ClassifyChart) is not made.
Trial Try(const TriMesh& piece, const MergeOptions& o, bool whole) {
    Trial t;
    if (piece.vertex_count() > o.max_chart_vertices)
        return t;
    t.param = FlattenChart(piece, o.param);
    const ChartParam& p = t.param;
    const bool flat = p.status == ParamStatus::kOk;
    const bool ok = flat && p.metrics.flipped == 0 && p.scale <= o.max_scale &&
                    p.metrics.jacobian_deviation_mean <= o.max_mean_deviation &&
                    CellSpread(piece, p.uv, 1 - p.metrics.virtual_fraction,
                               HorizonCells(p.scale, o)) <= o.max_cell_spread_deg;
    if (flat && (ok || whole))
        ClassifyChart(piece, o.param, &t.param);
    if (ok && p.status == ParamStatus::kOk)
        t.square = p.scale * p.scale;
    return t;
}

// The charts as they merge: faces, areas, each live chart's flattening and square.
struct MergeState {
    const TriMesh& mesh;
    const MergeOptions& options;
    std::vector<uint32_t>& chart;
    std::vector<std::vector<uint32_t>> faces_of;
    std::vector<double> area;
    std::vector<Trial> live;                           // square < 0: never merged
    std::vector<uint8_t> joined;                       // 1: a union of input charts
    std::vector<double> part_scale;  // sum over its input charts of area x their own scale
    std::set<std::pair<uint32_t, uint32_t>> rejected;  // pairs tried once and failed

    Trial TryUnion(const std::vector<uint32_t>& fa, const std::vector<uint32_t>& fb) const {
        thread_local std::vector<uint32_t> local_of;
        if (local_of.size() < mesh.vertex_count())
            local_of.assign(mesh.vertex_count(), kNoIndex);
        return Try(Union(mesh, fa, fb, local_of), options, /*whole=*/fb.empty());
    }

    // A matching from the ranked borders: each chart in at most one pair, pairs that cannot
    // pass or are not worth trying (too large, mostly fold, already failed, a chart that
    // fails on its own) left out.
    std::vector<Border> Pick(const std::vector<Border>& borders, size_t* folds) const {
        // The union's uv area is at most (1 - 2 margin)^2, so its square holds at least
        // its 3D area divided by that: over max_scale^2 it cannot pass.
        const double fill = 1 - 2 * options.param.margin;
        const double max_area = options.max_scale * options.max_scale * fill * fill;
        std::vector<uint8_t> matched(faces_of.size(), 0);
        std::vector<Border> picked;
        for (const Border& e : borders) {
            if (area[e.a] + area[e.b] > max_area ||
                faces_of[e.a].size() + faces_of[e.b].size() > options.max_union_triangles)
                continue;
            if (e.fold > options.max_fold_fraction * e.length) {
                ++*folds;
                continue;
            }
            if (matched[e.a] || matched[e.b] || live[e.a].square < 0 || live[e.b].square < 0 ||
                rejected.count({e.a, e.b}))
                continue;
            matched[e.a] = matched[e.b] = 1;
            picked.push_back(e);
        }
        return picked;
    }

    // Chart b joins chart a, which takes the union's flattening.
    void Join(uint32_t a, uint32_t b, Trial united) {
        for (uint32_t f : faces_of[b])
            chart[f] = a;
        faces_of[a].insert(faces_of[a].end(), faces_of[b].begin(), faces_of[b].end());
        std::sort(faces_of[a].begin(), faces_of[a].end());
        std::vector<uint32_t>().swap(faces_of[b]);
        live[a] = std::move(united);
        live[b] = Trial{};
        joined[a] = 1;
        area[a] += area[b];
        area[b] = 0;
        part_scale[a] += part_scale[b];
        part_scale[b] = 0;
    }
};

}  // namespace

MergeReport MergeCharts(const TriMesh& mesh, const MergeOptions& options,
                        std::vector<uint32_t>* chart_of, std::vector<ChartParam>* params,
                        std::vector<uint8_t>* united, std::vector<double>* parts_scale) {
    std::vector<uint32_t>& chart = *chart_of;
    if (params)
        params->clear();
    if (united)
        united->clear();
    if (parts_scale)
        parts_scale->clear();
    CHECK_EQ(chart.size(), mesh.triangle_count());
    MergeReport report;
    size_t chart_count = 0;
    for (uint32_t c : chart)
        chart_count = std::max<size_t>(chart_count, size_t(c) + 1);
    report.charts_before = report.charts_after = chart_count;
    if (chart_count < 2)
        return report;
    const Geometry g = Measure(mesh);
    const double fold_cos = std::cos(options.fold_deg * kPi / 180);
    MergeState st{mesh, options, chart, {}, {}, {}, {}, {}, {}};
    st.faces_of.resize(chart_count);
    st.area.assign(chart_count, 0);
    for (uint32_t f = 0; f < chart.size(); ++f) {
        st.faces_of[chart[f]].push_back(f);
        st.area[chart[f]] += g.area[f];
    }
    // Each chart's own flattening and square; a chart that fails on its own (the builder
    // splits it) is left alone.
    st.live.resize(chart_count);
    st.joined.assign(chart_count, 0);
    // The trials start largest first, so that a large one does not run alone at the end
    // (which thread runs a trial changes no result); so do each round's below.
    ParallelForInOrder(LargestFirst(chart_count, [&](size_t c) { return st.faces_of[c].size(); }),
                       [&](uint32_t c) { st.live[c] = st.TryUnion(st.faces_of[c], {}); });
    st.part_scale.resize(chart_count);
    for (size_t c = 0; c < chart_count; ++c)
        st.part_scale[c] = st.live[c].square >= 0 ? st.area[c] * st.live[c].param.scale : 0;

    for (int round = 0; round < options.max_rounds; ++round) {
        size_t folds = 0;
        const std::vector<Border> picked =
            st.Pick(Borders(g, chart, chart_count, fold_cos), &folds);
        if (round == 0)
            report.rejected_fold = folds;
        if (picked.empty())
            break;
        ++report.rounds;
        report.tried += picked.size();
        std::vector<Trial> trials(picked.size());
        const auto union_faces = [&](size_t i) {
            return st.faces_of[picked[i].a].size() + st.faces_of[picked[i].b].size();
        };
        ParallelForInOrder(LargestFirst(picked.size(), union_faces), [&](uint32_t i) {
            trials[i] = st.TryUnion(st.faces_of[picked[i].a], st.faces_of[picked[i].b]);
        });
        for (size_t i = 0; i < picked.size(); ++i) {
            const Border& e = picked[i];
            const double sq = trials[i].square;
            const double parts = st.live[e.a].square + st.live[e.b].square;
            if (sq < 0 || sq > (1 + options.max_square_growth) * parts) {
                st.rejected.insert({e.a, e.b});
                continue;
            }
            st.Join(e.a, e.b, std::move(trials[i]));
            ++report.accepted;
        }
    }
    // Renumber by smallest triangle index.
    std::vector<uint32_t> remap(chart_count, kNoIndex);
    uint32_t next = 0;
    for (uint32_t& c : chart) {
        if (remap[c] == kNoIndex) {
            remap[c] = next++;
            if (params)
                params->push_back(std::move(st.live[c].param));
            if (united)
                united->push_back(st.joined[c]);
            if (parts_scale)
                parts_scale->push_back(st.area[c] > 0 ? st.part_scale[c] / st.area[c] : 0);
        }
        c = remap[c];
    }
    report.charts_after = next;
    return report;
}

}  // namespace mebake::stream
