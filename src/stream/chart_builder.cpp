#include "stream/chart_builder.h"

#include "core/check.h"
#include "core/error.h"
#include "core/log.h"
#include "core/paged_file.h"
#include "core/parallel.h"
#include "stream/bricks.h"
#include "stream/chart_grid.h"
#include "stream/chart_merge.h"
#include "stream/parameterize.h"
#include "stream/segment.h"
#include "stream/spill.h"
#include "stream/tile.h"
#include "stream/work_order.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <optional>

namespace mebake::stream {

namespace {

// The power of two nearest (in log scale) to the texels the chart's square needs.
uint32_t ResolutionFor(double scale, const ChartBuildOptions& opt) {
    return ChartResolution(scale, opt.texel_size, opt.min_resolution, opt.max_resolution);
}

// Samples the master element into the finest level of its geometry image.
GeometryImage SampleGeometry(const TriMesh& chart, const ChartParam& param, const ChartGrid& grid,
                             const std::vector<Vec3f>& normals, uint32_t res) {
    GeometryImage img;
    img.resolution = res;
    int levels = 0;
    while ((1u << levels) < res)
        ++levels;
    img.levels.resize(size_t(levels) + 1);
    auto& fine = img.levels.back();
    fine.resize(size_t(res) * res);
    const int k = 2;  // sub-samples per texel side, for coverage and area
    const double texel_uv = 1.0 / res;
    const double s2 = param.scale * param.scale;
    // Rows in parallel (each texel is written by its own iteration only).
    ParallelFor(0, int64_t(res), [&](int64_t row) {
        const uint32_t j = uint32_t(row);
        for (uint32_t i = 0; i < res; ++i) {
            GeometryTexel& t = fine[size_t(j) * res + i];
            Vec2f centre(float((i + 0.5) * texel_uv), float((j + 0.5) * texel_uv));
            SurfacePoint sp = Evaluate(grid, chart.position, normals, centre);
            t.position = sp.position;
            t.normal = sp.normal;
            t.vis_point = sp.visible_position;
            uint32_t tri = sp.triangle;
            double area = 0;
            int real = 0;
            for (int b = 0; b < k; ++b) {
                for (int a = 0; a < k; ++a) {
                    Vec2f u(float((i + (a + 0.5) / k) * texel_uv),
                            float((j + (b + 0.5) / k) * texel_uv));
                    const uint32_t inside = grid.InsideTriangle(u);
                    if (inside == kNoTriangle)
                        continue;
                    ++real;
                    area += double(param.area_ratio[inside]) * s2 * texel_uv * texel_uv / (k * k);
                }
            }
            t.area = float(area);
            t.coverage = float(real) / float(k * k);
            t.radius = float(0.75 * texel_uv * param.scale);
            if (tri != kNoTriangle) {
                t.material = chart.material[tri];
                if (!chart.albedo.empty()) {
                    GridLocation loc =
                        grid.Locate(sp.real ? centre : grid.Locate(centre).nearest_uv);
                    Vec3f c{};
                    bool ok = true;
                    for (int v = 0; v < 3; ++v) {
                        const Vec3f& a = chart.albedo[chart.triangles[loc.triangle][size_t(v)]];
                        ok &= a.x >= 0;
                        c += a * loc.barycentric[size_t(v)];
                    }
                    t.color = ok ? c : Vec3f(-1, -1, -1);
                } else {
                    t.color = Vec3f(-1, -1, -1);
                }
            }
        }
    });
    img.BuildPyramid();
    return img;
}

// Adds the time since the last Lap (or construction) to one stage's total.
class StageClock {
public:
    explicit StageClock(std::array<double, kChartStageNames.size()>* totals)
        : totals_(totals), last_(Clock::now()) {}
    void Lap(size_t stage) {
        const auto now = Clock::now();
        (*totals_)[stage] += std::chrono::duration<double>(now - last_).count();
        last_ = now;
    }

private:
    using Clock = std::chrono::steady_clock;
    std::array<double, kChartStageNames.size()>* totals_;
    Clock::time_point last_;
};
enum Stage : size_t { kLoad, kRepair, kSegment, kParameterize, kGrid, kGeometry, kWrite };

// Normals over a whole repaired brick, looked up by global vertex id; copies made by
// manifold splitting share an id and are averaged.
class BrickNormals {
public:
    explicit BrickNormals(const TriMesh& mesh) {
        const std::vector<Vec3f> n = VertexNormals(mesh.position, mesh.triangles);
        normals_.reserve(n.size());
        for (size_t v = 0; v < n.size(); ++v)
            normals_.emplace_back(mesh.vertex_id[v], n[v]);
        std::sort(normals_.begin(), normals_.end(),
                  [](const auto& a, const auto& b) { return a.first < b.first; });
        size_t kept = 0;
        for (size_t k = 0; k < normals_.size();) {
            size_t e = k;
            Vec3f sum{};
            while (e < normals_.size() && normals_[e].first == normals_[k].first)
                sum += normals_[e++].second;
            normals_[kept++] = {normals_[k].first, Normalize(sum)};
            k = e;
        }
        normals_.resize(kept);
    }
    // The normal of vertex `id`, or `fallback` when it has none.
    Vec3f At(uint64_t id, const Vec3f& fallback) const {
        auto it = std::lower_bound(normals_.begin(), normals_.end(), id,
                                   [](const auto& a, uint64_t x) { return a.first < x; });
        return it != normals_.end() && it->first == id && Length(it->second) > 0 ? it->second
                                                                                 : fallback;
    }

private:
    std::vector<std::pair<uint64_t, Vec3f>> normals_;
};

// A chart from the segmentation (or the merge) waiting for its tile.
struct Pending {
    TriMesh chart;
    int depth = 0;
    ChartParam param;
    bool united = false;     // a union from the merge (its own geometry resolution)
    double parts_scale = 0;  // of a union: its parts' mean square side (chart_merge.h)
};

// What one chart of the segmentation became: its tiles, in order (itself, or the parts
// its splits made, depth first).
struct RootResult {
    std::vector<ChartRecord> charts;
    std::vector<std::string> tile_files;
    uint64_t splits = 0;
    std::array<uint64_t, 4> split_for{};  // distorted, flipped or overlapping, not a disc, other
    std::array<double, kChartStageNames.size()> stage_seconds{};
};
}  // namespace

uint32_t UnionEmitterResolution(double scale, double parts_scale, uint32_t geometry_resolution,
                                const ChartBuildOptions& opt) {
    if (!(parts_scale > 0) || !(scale > parts_scale))
        return 0;
    // Samples as small as the parts' on average (the nearest power of two: within a factor
    // sqrt(2)), but no finer than the geometry the solver samples them from.
    const double want = opt.emitter_samples * scale / parts_scale;
    uint32_t n = opt.emitter_samples;
    while (n * std::sqrt(2.0) < want && n < geometry_resolution)
        n *= 2;
    return n > opt.emitter_samples ? n : 0;
}

// cos 30 degrees: beyond this a chart's own vertex normal and the brick's disagree because
// the surface folds there, not because of noise.
constexpr float kCreaseCos = 0.866f;

namespace {

// The index in RootResult::split_for of why a chart was split.
size_t SplitReason(ParamStatus status) {
    if (status == ParamStatus::kDistorted)
        return 0;
    if (status == ParamStatus::kFlipped || status == ParamStatus::kOverlap)
        return 1;
    return status == ParamStatus::kNotDisc ? 2 : 3;
}

// One chart of the segmentation through to its tiles: parameterized (unless the merge did
// it), split in two and both halves back at the front of its queue when it fails (not a
// disc, flipped or overlapping, too distorted), so the order of its parts is fixed; each
// part's grid, geometry image and tile. It reads only its own chart and writes only its
// own files (named after `root`), so the charts of a brick can be built in parallel.
RootResult BuildFromRoot(const std::string& dir, uint32_t brick, uint32_t root, Pending first,
                         const BrickNormals& brick_normals, const ParamOptions& popt,
                         const ChartBuildOptions& opt) {
    RootResult out;
    StageClock clock(&out.stage_seconds);
    std::deque<Pending> queue;
    queue.push_back(std::move(first));
    while (!queue.empty()) {
        Pending item = std::move(queue.front());
        queue.pop_front();
        TriMesh& chart = item.chart;
        const int depth = item.depth;
        if (chart.triangles.empty())
            continue;
        ChartParam param = item.param.status != ParamStatus::kEmpty
                               ? std::move(item.param)
                               : ParameterizeChart(chart, popt);
        clock.Lap(kParameterize);
        const bool can_split = chart.triangles.size() > 1 && depth < 24;
        if (param.status != ParamStatus::kOk && can_split &&
            (param.status == ParamStatus::kDistorted || !HasUv(param.status) ||
             param.status == ParamStatus::kFlipped || param.status == ParamStatus::kOverlap)) {
            std::vector<uint32_t> half = SplitChart(chart, 2);
            uint32_t parts = 0;
            for (uint32_t h : half)
                parts = std::max(parts, h + 1);
            if (parts >= 2) {
                ++out.splits;
                ++out.split_for[SplitReason(param.status)];
                for (uint32_t p = parts; p-- > 0;)
                    queue.push_front({ExtractChart(chart, half, p), depth + 1, {}});
                clock.Lap(kSegment);
                continue;
            }
        }
        if (!HasUv(param.status))
            InputError({dir}, "brick {}: a chart of {} triangles cannot be parameterized ({}: {})",
                       brick, chart.triangles.size(), ParamStatusName(param.status), param.message);

        ChartTile tile;
        tile.position = chart.position;
        // The brick-wide normal, unless it is degenerate or the chart meets its neighbour
        // at a crease (a box's edge): there each side keeps its own normal, as a smoothing
        // angle would.
        tile.normal = VertexNormals(chart.position, chart.triangles);
        for (size_t v = 0; v < tile.normal.size(); ++v) {
            const Vec3f shared = brick_normals.At(chart.vertex_id[v], tile.normal[v]);
            if (Dot(shared, tile.normal[v]) >= kCreaseCos)
                tile.normal[v] = shared;
        }
        tile.uv = param.uv;
        if (!chart.albedo.empty())
            tile.color = chart.albedo;
        tile.vertex_id = chart.vertex_id;
        tile.triangles = chart.triangles;
        tile.face_id = chart.face_id;
        tile.material = chart.material;
        int grid_res = DefaultGridResolution(chart.triangles.size());
        tile.grid = BuildChartGrid(tile.uv, tile.triangles, grid_res);
        clock.Lap(kGrid);
        const uint32_t res = ResolutionFor(param.scale, opt);
        tile.geometry = SampleGeometry(
            chart, param, tile.grid, tile.normal,
            std::min(res, item.united ? opt.union_geometry_resolution : opt.max_geometry_resolution));
        clock.Lap(kGeometry);

        ChartMeta& m = tile.meta;
        m.brick = brick;
        m.vertex_count = uint32_t(chart.position.size());
        m.triangle_count = uint32_t(chart.triangles.size());
        m.resolution = res;
        m.grid_resolution = uint32_t(grid_res);
        if (item.united)
            m.emitter_resolution = UnionEmitterResolution(param.scale, item.parts_scale,
                                                          tile.geometry.resolution, opt);
        m.scale = param.scale;
        m.area = param.metrics.area_3d;
        m.jacobian_deviation = param.metrics.jacobian_deviation_mean;
        m.jacobian_deviation_max = param.metrics.jacobian_deviation_max;
        m.virtual_fraction = param.metrics.virtual_fraction;
        m.flipped = param.metrics.flipped;
        m.bbox_min = Vec3f(1e30f, 1e30f, 1e30f);
        m.bbox_max = Vec3f(-1e30f, -1e30f, -1e30f);
        for (const auto& p : chart.position) {
            m.bbox_min = Min(m.bbox_min, p);
            m.bbox_max = Max(m.bbox_max, p);
        }
        char name[64];
        std::snprintf(name, sizeof(name), "/tiles/b%05u-%05u-%03zu.tile", brick, root,
                      out.tile_files.size());
        std::string path = dir + name;
        WriteTile(path, tile);
        clock.Lap(kWrite);
        out.tile_files.push_back(path);
        ChartRecord rec;
        rec.brick = brick;
        rec.triangles = m.triangle_count;
        rec.vertices = m.vertex_count;
        rec.resolution = res;
        rec.scale = m.scale;
        rec.area = m.area;
        rec.area_distortion = m.jacobian_deviation;
        rec.virtual_fraction = m.virtual_fraction;
        rec.bbox_min = m.bbox_min;
        rec.bbox_max = m.bbox_max;
        out.charts.push_back(rec);
    }
    return out;
}

}  // namespace

BrickResult BuildBrickCharts(const std::string& dir, uint32_t brick, const ChartBuildOptions& opt) {
    BrickResult out;
    StageClock clock(&out.stage_seconds);
    std::vector<uint8_t> on_cut;
    TriMesh mesh = LoadBrick(dir, brick, opt.cache_bytes, &on_cut);
    clock.Lap(kLoad);
    if (mesh.triangles.empty())
        return out;
    out.repair = Repair(mesh, on_cut, RepairOptions{});
    // The caller keeps every brick's result to the end of the ingest: the report's counts,
    // not its per-vertex cut flags (1 B per vertex of the whole mesh, 50 MB at 100M
    // triangles: the ingest's peak grew with the mesh; bench/RESULTS.md, issue 16 session 12).
    std::vector<uint8_t>().swap(out.repair.vertex_on_cut);
    clock.Lap(kRepair);

    // The proxy's copy of the brick, and normals over the whole repaired brick (so a vertex
    // on a chart border has the same normal in every chart that holds it: per-chart
    // normals made seams), do not depend on the charts: they are made on another core
    // while the segmentation, whose Lloyd floods run on one, goes on. (The merge's face
    // geometry made there too cost the ingest's peak +21 MB on igea for ~20 ms on the
    // horse; it is measured after the segmentation, whose arrays are freed by then.)
    std::optional<BrickNormals> brick_normals;
    TaskGroup beside;
    beside.Run([&] {
        out.proxy_positions = mesh.position;
        out.proxy_triangles.reserve(mesh.triangles.size() * 3);
        for (const auto& t : mesh.triangles)
            out.proxy_triangles.insert(out.proxy_triangles.end(), t.begin(), t.end());
        brick_normals.emplace(mesh);
    });
    SegmentOptions sopt;
    sopt.max_chart_vertices = opt.max_chart_vertices;
    sopt.lloyd_iterations = opt.lloyd_iterations;
    SegmentReport sreport;
    std::vector<uint32_t> chart_of = SegmentCharts(mesh, sopt, &sreport);
    beside.Wait();
    ParamOptions popt;
    popt.max_jacobian_deviation = opt.max_distortion;
    popt.refine_options.max_iterations = opt.refine_iterations;
    MergeReport mreport;
    std::vector<ChartParam> merged_params;  // per chart after merging, when computed
    std::vector<uint8_t> united;            // per chart after merging: 1 for a union
    std::vector<double> parts_scale;        // per chart after merging: its parts' mean square
    if (opt.merge_charts) {
        MergeOptions mopt;
        mopt.param = popt;
        mopt.max_chart_vertices = opt.max_chart_vertices;
        mopt.max_union_triangles = sopt.target_chart_faces;
        // ResolutionFor rounds up from want / sqrt(2): a union under this scale gets a
        // square of at most max_merged_resolution texels (and never more than
        // max_resolution, so it keeps every light-map texel it asks for).
        const uint32_t merged_res = std::min(opt.max_resolution, opt.max_merged_resolution);
        mopt.max_scale = merged_res *
                         (opt.merge_horizon_cells ? opt.max_union_texel : std::sqrt(2.0)) *
                         opt.texel_size;
        // The turn bound stays on 8 x 8 cells per union (texel_size 0): with cells of 8
        // texels lucy merged to 86 charts but its error against the path tracer rose from
        // 4.65 % to 6.33 %, its 512-texel charts' indirect light 18-24 % low from the
        // solver's 32 x 32 emitter samples per chart (bench/RESULTS.md, "Issue 13 (session
        // 9)"; docs/method.md, "Merging").
        if (opt.merge_horizon_cells) {
            mopt.texel_size = opt.texel_size;
            mopt.min_resolution = opt.min_resolution;
            mopt.max_resolution = opt.max_resolution;
        }
        mreport = MergeCharts(mesh, mopt, &chart_of, &merged_params, &united, &parts_scale);
    }

    std::vector<Pending> roots;
    {
        std::vector<TriMesh> charts = ExtractCharts(mesh, chart_of);
        roots.resize(charts.size());
        for (size_t c = 0; c < charts.size(); ++c) {
            roots[c].chart = std::move(charts[c]);
            // A chart straight from the merge comes with its parameterization (the same
            // bits ParameterizeChart would give here).
            if (merged_params.size() == charts.size())
                roots[c].param = std::move(merged_params[c]);
            roots[c].united =
                opt.merge_horizon_cells && united.size() == charts.size() && united[c];
            if (roots[c].united)
                roots[c].parts_scale = parts_scale[c];
        }
    }
    clock.Lap(kSegment);
    // The charts in parallel, largest first (a large chart left to the end would run
    // alone); their tiles are listed in chart order, so the order of the work changes no
    // byte.
    const std::vector<uint32_t> order =
        LargestFirst(roots.size(), [&](size_t c) { return roots[c].chart.triangles.size(); });
    std::vector<RootResult> built(roots.size());
    ParallelForInOrder(order, [&](uint32_t c) {
        built[c] = BuildFromRoot(dir, brick, c, std::move(roots[c]), *brick_normals, popt, opt);
    });
    uint64_t split_for[4] = {};
    for (RootResult& r : built) {
        out.charts.insert(out.charts.end(), r.charts.begin(), r.charts.end());
        out.tile_files.insert(out.tile_files.end(), r.tile_files.begin(), r.tile_files.end());
        out.splits += r.splits;
        for (size_t k = 0; k < 4; ++k)
            split_for[k] += r.split_for[k];
        for (size_t k = 0; k < out.stage_seconds.size(); ++k)
            out.stage_seconds[k] += r.stage_seconds[k];
    }
    // Where the charts come from (mebake -v): seeds, what the segmentation inserted,
    // split and merged, and what the parameterization split again.
    spdlog::debug("brick {}: {} faces, {} components: {} seeds + {} inserted (deviation or "
                  "size) + {} leftovers, {} disc splits, {} small merged -> {} charts; "
                  "{} rounds merged {} of {} pairs tried ({} borders mostly fold) -> {} charts; "
                  "parameterization splits: {} distorted, {} flipped or overlapping, {} not a disc, {} other "
                  "-> {} charts",
                  brick, mesh.triangles.size(), sreport.components, sreport.initial_seeds,
                  sreport.inserted_seeds, sreport.leftover_charts, sreport.split_charts,
                  sreport.merged_charts, sreport.charts, mreport.rounds, mreport.accepted,
                  mreport.tried, mreport.rejected_fold, mreport.charts_after, split_for[0],
                  split_for[1], split_for[2], split_for[3], out.charts.size());
    return out;
}

}  // namespace mebake::stream
