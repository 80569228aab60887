// A solved bake directory opened for output (export, render), and the shading of one chart
// from its tile at full geometric detail: every output — light maps, irradiance maps,
// per-vertex colours, rendered views, the seam metric — evaluates lighting through
// ChartShader, so they agree to the bit.
//
// ChartShader follows the seed paper's display rule B(x) = Be + rho(x) (n(x) . E(x))+ with
// n and rho from the tile's own mesh (interpolated vertex normals and colours, the
// triangle's material) and E from the chart's field at the same chart point. A point of the
// master element's virtual part takes normal, colour and material from its nearest real
// point (the seed paper's "nearest real triangle"), while E is still evaluated where the
// point is, so texels that straddle the chart's outline filter smoothly. E is the chart's
// field as continuous_field.h reconstructs it (C0 across quadtree node borders), stitched to
// its neighbours at chart borders (seam_stitch.h, when the view has the stitch data).
#pragma once

#include "core/memory_budget.h"
#include "core/parallel.h"
#include "core/vec.h"
#include "output/continuous_field.h"
#include "output/seam_stitch.h"
#include "solve/field.h"
#include "solve/scene.h"
#include "solve/solution.h"
#include "stream/bake_dir.h"
#include "stream/tile.h"

#include <algorithm>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace mebake::output {

class SeamStitcher;

// The solver's types every output reads.
using solve::ChartField;
using solve::Material;
using solve::Scene;
using solve::Solution;
using solve::SolutionReader;

struct BakeView {
    std::string dir;
    stream::Manifest manifest;
    Scene scene;
    Solution solution;  // fields empty when opened with FieldLoading::OnDemand
    std::shared_ptr<const SolutionReader> solution_reader;  // OnDemand only
    std::shared_ptr<const SeamStitcher> stitcher;  // seam_graph.h; null: not stitched

    size_t chart_count() const { return manifest.charts.size(); }
    std::string TilePath(uint32_t chart) const { return stream::TilePath(dir, chart); }
    // Chart c's field: solution.fields[c], or read from solve/solution.bin on demand (then
    // the pointer owns it). Thread-safe.
    std::shared_ptr<const ChartField> Field(uint32_t c) const;
    bool stitched() const { return stitcher != nullptr; }
    // Chart c's stitch data, built on demand from the tiles around it (seam_graph.h), or
    // nullptr when the view is not stitched. Thread-safe.
    std::shared_ptr<const ChartSeams> Seams(uint32_t c) const;
};

// All: every chart's field is read and checked at open (render and reference, which
// look lighting up anywhere). OnDemand: one chart's at a time through BakeView::Field, so
// resident memory follows the charts being written (export).
enum class FieldLoading { All, OnDemand };

// On: the fields are stitched across chart borders (seam_graph.h; one more pass over the
// tiles at open). Off: each chart shows its own field (to measure what stitching changes).
enum class SeamStitching { On, Off };

// Reads the manifest, solve/solution.bin and the scene the solve used (solve/scene.json
// when the solve had one, else the inputs' materials and the default rig). The stitch data
// is built chart by chart when asked for; `stitch_cache_bytes` caps the charts' sampled
// borders kept between requests (it changes the time, not the bytes). Throws
// Error(Usage) when the directory is not ingested or not solved, Error(Corrupt) naming the
// file when the solution does not match the charts.
BakeView OpenBakeView(const std::string& dir, FieldLoading fields = FieldLoading::All,
                      SeamStitching stitching = SeamStitching::On,
                      size_t stitch_cache_bytes = MemoryBudget(uint64_t(1) << 30).StitchCache());

// The resolution of every chart from the manifest, validated (Error(Corrupt) otherwise).
std::vector<uint32_t> ChartResolutions(const BakeView& view);

// Reads the tiles of `charts` in parallel batches; for each, prepare(chart, tile) runs in
// parallel and returns a result, then consume(chart, tile, result) runs on the calling
// thread in the order of `charts` — so whatever consume accumulates is deterministic.
// Memory: one batch of tiles (`batch` tiles; 0 = 2 per worker thread).
template <typename Prepare, typename Consume>
void ForEachTile(const BakeView& view, std::span<const uint32_t> charts, stream::TileParts parts,
                 Prepare&& prepare, Consume&& consume, size_t batch = 0) {
    using Result = decltype(prepare(uint32_t(0), std::declval<stream::ChartTile&>()));
    if (batch == 0)
        batch = size_t(std::max(1, 2 * MaxThreads()));
    std::vector<stream::ChartTile> tiles;
    std::vector<Result> results;
    for (size_t first = 0; first < charts.size(); first += batch) {
        const size_t n = std::min(batch, charts.size() - first);
        tiles.assign(n, {});
        results.assign(n, Result{});
        ParallelFor(0, int64_t(n), [&](int64_t k) {
            const uint32_t c = charts[first + size_t(k)];
            tiles[size_t(k)] = stream::ReadTile(view.TilePath(c), parts);
            results[size_t(k)] = prepare(c, tiles[size_t(k)]);
        });
        for (size_t k = 0; k < n; ++k)
            consume(charts[first + k], tiles[k], results[k]);
    }
}

// 0, 1, ..., chart_count - 1.
std::vector<uint32_t> AllCharts(const BakeView& view);

// What shading needs at a surface point of a chart.
struct ShadingPoint {
    Vec2f uv;      // chart point where the field is evaluated
    Vec3f normal;  // unit
    Vec3f albedo;  // linear
    const Material* material = nullptr;
};

class ChartShader {
public:
    // Keeps references to tile, field and scene, and the seams (BakeView::Seams; nullptr:
    // the field as fitted at chart borders). Throws Error(Corrupt) naming `tile_path` when a
    // triangle's material is not in the scene.
    ChartShader(const stream::ChartTile& tile, const ChartField& field, bool radiosity_unknown,
                const Scene& scene, const std::string& tile_path,
                std::shared_ptr<const ChartSeams> seams = nullptr);

    // The point of triangle t with barycentrics (b0, b1, b2) (they need not sum to 1
    // exactly; weights are used as given).
    ShadingPoint AtTriangle(uint32_t t, float b0, float b1, float b2) const;
    // Chart point u (clamped to the unit square), located in the chart's grid.
    ShadingPoint AtUv(Vec2f u) const;
    // AtUv(u) when u lies in a triangle of the chart (ChartGrid::InsideTriangle's test,
    // the same location), nullopt in the virtual part: one search for both, and none for
    // the virtual part's nearest triangle (ChartGrid::LocateReal).
    std::optional<ShadingPoint> AtUvInside(Vec2f u) const;
    // Tile vertex v: its own uv, normal and colour; the material of the lowest-index
    // triangle that uses it (the default material if none does).
    ShadingPoint AtVertex(uint32_t v) const;

    // Radiosity B (W/m^2 per channel), finite and >= 0.
    Vec3f Radiosity(const ShadingPoint& p) const;
    // Radiance towards `view` (unit, surface to eye) with the glossy display approximation.
    Vec3f Glossy(const ShadingPoint& p, const Vec3f& view) const;
    // Vector irradiance E at chart point uv, per colour (zero for a radiosity solution).
    void Irradiance(Vec2f uv, Vec3f e[3]) const;

    // The shown field's blocks at chart point uv (field.blocks() floats).
    void FieldAt(Vec2f uv, float* val) const;

    const stream::ChartTile& tile() const { return tile_; }

private:
    // The point at u where the grid located it (a default point for a chart without triangles).
    ShadingPoint AtLocation(Vec2f u, const stream::GridLocation& loc) const;
    Vec3f Color(uint32_t v) const;
    // The tile's vertex normals, with the stitched ones at chart borders.
    const std::vector<Vec3f>& Normals() const { return normal_.empty() ? tile_.normal : normal_; }

    const stream::ChartTile& tile_;
    const ChartField& field_;
    ContinuousField display_;  // the field as shown: C0 across node borders
    std::shared_ptr<const ChartSeams> seams_;  // and stitched across chart borders
    bool radiosity_;
    const Scene& scene_;
    std::vector<uint32_t> vertex_triangle_;  // lowest triangle using each vertex
    std::vector<Vec3f> normal_;              // empty: the tile's own
    Material default_material_;
};

}  // namespace mebake::output
