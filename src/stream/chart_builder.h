// Ingest pass 3, per brick: the brick's faces in core -> repair -> charts (discs) ->
// near-isometric parameterization in the unit square, split and redone while the
// Jacobian deviation is over the threshold -> point-location grid -> geometry image ->
// one tile per chart. Runs for many bricks in parallel; each call touches only its
// own brick's files.
#pragma once

#include "core/vec.h"
#include "stream/bake_dir.h"
#include "stream/repair.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace mebake::stream {

// Stages of BuildBrickCharts, timed separately (BrickResult::stage_seconds).
inline constexpr std::array<const char*, 7> kChartStageNames = {
    "load", "repair", "segment", "parameterize", "grid", "geometry", "write"};

struct ChartBuildOptions {
    double texel_size = 0.01;     // 3D size of a light-map texel
    uint32_t min_resolution = 4;  // light-map texels per chart side, powers of two
    uint32_t max_resolution = 2048;
    // The geometry image the solver samples is at most this fine; the light map itself
    // is evaluated from the triangles at the chart's full resolution by export. Merged
    // charts did not need more: on the bunny (15 charts of up to 512 texels) 512 instead
    // of 128 gave the same error against the path tracer (3.43 % / 3.44 %) and a slower
    // solve (21.8 s against 11.8 s, loaded 2-core machine).
    uint32_t max_geometry_resolution = 128;
    // Merged charts' squares are at most this many texels a side (chart_merge.h), the
    // largest the segmentation made before merging on the shared scans: the solver's
    // per-chart budgets (8192 quadtree nodes, 32 x 32 emitter samples; solve/solver.h)
    // were tuned on such charts (1024-texel charts: bunny 6.74 % against 2.50 %).
    uint32_t max_merged_resolution = 512;
    double max_distortion = 0.05;  // split charts whose Jacobian deviation is above
    uint32_t max_chart_vertices = 50000;
    // Cheaper than the library defaults (16 and 6). Measured: mean area distortion bunny
    // 0.28% -> 0.30%, lucy 0.45% -> 0.51%; CPU time of the whole ingest -20% (1M sphere)
    // to -35% (lucy). Charts over max_distortion are still split.
    int refine_iterations = 8;             // local/global iterations of the parameterization
    int lloyd_iterations = 4;              // segmentation passes before the first bound check
    // Merge neighbouring charts while their union still parameterizes within the rule
    // (chart_merge.h).
    bool merge_charts = true;
    // Bound the union's turning on cells of 8 light-map texels instead of 8 x 8 cells per
    // chart: fewer charts (lucy 86 against 237), less accurate on five of seven scans (see
    // chart_builder.cpp).
    bool merge_horizon_cells = false;
    // With merge_horizon_cells, a union's geometry image is at most this many texels a side
    // (other charts: max_geometry_resolution), so a 512-texel union samples its geometry
    // every 2 x 2 texels, as a 256-texel chart does, not every 4 x 4: the turbine blade's
    // thin edges on 512-texel unions came out 45-74 % dark at 128 (merged + emitter_texels 4:
    // +0.87 -> +0.15 point against main at the same points; 512 samples leaked light in the
    // horse's folds, +0.95; bench/RESULTS.md, "Issue 13 (session 16)").
    uint32_t union_geometry_resolution = 256;
    // With merge_horizon_cells, a union's emitter samples are no larger than its parts'
    // were (ChartMeta::emitter_resolution): the solver gives every chart this many emitter
    // samples a side (solve/solver.h, max_emitter_level), so a union of four 128-texel
    // charts into a 512-texel one would otherwise sample its light every 16 texels
    // instead of every 4, and lucy's merged charts lost bounced light (bench/RESULTS.md,
    // "Issue 13 (session 18)").
    uint32_t emitter_samples = 32;
    // With merge_horizon_cells, a union's texel is at most this many times texel_size (the
    // default merge: sqrt(2), the most ResolutionFor gives any chart). At sqrt(2) lucy's
    // unions grew to 512 texels of 1.16 nominal texels on average (default ingest 1.05)
    // and their direct light lost detail; at 1.2 the merged ingests' texels are the default
    // ingest's within -0.11..+0.07 of nominal on the seven scans, lucy 90 charts
    // (bench/RESULTS.md, "Issue 13 (session 18)").
    double max_union_texel = 1.2;
    size_t cache_bytes = size_t(3) << 20;  // vertex look-ups for this brick (ascending ids)
};

struct BrickResult {
    std::vector<ChartRecord> charts;      // in tile order
    std::vector<std::string> tile_files;  // temporary names, renamed by the caller
    RepairReport repair;  // its counts (vertex_on_cut left empty)
    uint64_t splits = 0;  // charts split for distortion or topology
    // Seconds spent per stage in this brick (wall time of the calling thread), in the
    // order of kChartStageNames.
    std::array<double, kChartStageNames.size()> stage_seconds{};
    // The brick's repaired surface, for the visibility mesh.
    std::vector<Vec3f> proxy_positions;
    std::vector<uint32_t> proxy_triangles;
};

// The emitter samples a side (ChartMeta::emitter_resolution) of a union of square side
// `scale` whose parts' mean square side was parts_scale: enough that its samples are no
// larger than the parts' (opt.emitter_samples each), at most geometry_resolution; 0 when
// the solver's own opt.emitter_samples are fine enough.
uint32_t UnionEmitterResolution(double scale, double parts_scale, uint32_t geometry_resolution,
                                const ChartBuildOptions& opt);

BrickResult BuildBrickCharts(const std::string& dir, uint32_t brick, const ChartBuildOptions& opt);

}  // namespace mebake::stream
