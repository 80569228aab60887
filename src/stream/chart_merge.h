// Merging neighbouring charts after segmentation, so that charts are as large as the
// parameterization rule allows. The segmentation's normal-cone bound and its fold rule are
// cheap stand-ins for "this piece flattens well"; on scans they cut far more often than the
// flattening needs (lucy: 4 seeds, 353 inserted for the cone). Here two neighbouring charts
// become one when their union is a disc whose parameterization (parameterize.h) passes the
// same test a chart must pass anyway (no flips, coarse Jacobian deviation within the
// bound), with a mean Jacobian deviation within MergeOptions::max_mean_deviation.
#pragma once

#include "stream/parameterize.h"
#include "stream/trimesh.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mebake::stream {

struct MergeOptions {
    ParamOptions param;                 // the flattening each union must pass
    double max_mean_deviation = 0.01;   // jacobian_deviation_mean of a union (the seed's 1 %)
    // A union's square (in 3D area) may exceed its two charts' squares together by this
    // fraction at most: merging must not make the light map larger (an L-shaped union
    // wastes most of its square).
    double max_square_growth = 0.25;
    uint32_t max_chart_vertices = 50000;
    // Unions of more triangles are not tried: charts that size are no longer what makes
    // the chart count high, and flattening them is what merging costs (the 1M sphere's
    // 27K-triangle charts merged into 18 cost 10 CPU-s of ingest, more than the solve
    // gained). The chart builder passes the segmentation's target chart size.
    uint32_t max_union_triangles = 30000;
    // How far a union's surface may turn inside one cell (degrees; chart_merge.cpp,
    // CellSpread; the bound was made for the solver's former 8 x 8 horizon): cells of 2^kHorizonCellLevels light-map
    // texels, at least 8 x 8 per chart (geometry_image.h, HorizonLevel), given texel_size;
    // with texel_size 0, 8 x 8 cells per chart. With 8 x 8 cells per chart whatever its size
    // (before the solver's horizon followed the texel), measured on the bunny against the
    // path tracer (the same 1959 points, M2): no bound, 15 charts, 3.43 % RMS (max 83 %, at
    // an ear tip); 25 degrees, 23 charts, 2.64 %; 20 degrees, 28 charts, 2.55 %; unmerged,
    // 37 charts, 2.50 %.
    double max_cell_spread_deg = 20;
    // Largest square side in 3D units (ParamChart::scale): the light map's largest chart
    // resolution times the texel size, so that a union never loses light-map texels.
    double max_scale = 1e300;
    // The light map's texel (3D units) and its range of chart resolutions (chart_builder.h),
    // for the union's resolution, which sets its horizon cells.
    double texel_size = 0;
    uint32_t min_resolution = 4;
    uint32_t max_resolution = 2048;
    // A border that is mostly fold (faces meeting at more than this angle) is a real edge
    // of the shape: the charts on both sides stay apart.
    double fold_deg = 70;
    double max_fold_fraction = 0.5;  // of the shared border's length
    int max_rounds = 64;             // each round merges a matching of pairs
};

struct MergeReport {
    size_t charts_before = 0;
    size_t charts_after = 0;
    size_t rounds = 0;
    size_t tried = 0;     // unions parameterized
    size_t accepted = 0;  // = charts_before - charts_after
    size_t rejected_fold = 0;  // pairs never tried: their border is mostly fold
};

// chart_of: chart id per triangle of `mesh` (ids 0..n-1, every chart a disc, as
// SegmentCharts makes them). Rewrites it with merged charts, renumbered by smallest
// triangle index. Deterministic for any thread count (pairs are chosen in a fixed order,
// unions are parameterized in parallel, results applied in that order). If params is
// given and there were at least two charts, (*params)[c] receives final chart c's
// ParameterizeChart(ExtractCharts(mesh, *chart_of)[c], options.param) (status kEmpty
// where it was never computed: a chart over the vertex bound), so the caller need not
// compute it again. If united is given, (*united)[c] is 1 where final chart c is a union
// of two or more of the input charts, 0 where it is an input chart as it was. If
// parts_scale is given, (*parts_scale)[c] is the mean square side (ParamChart::scale) of
// final chart c's input charts, weighted by their 3D area: the size of the squares its
// surface had before merging (its own scale for an input chart; 0 for one that failed on
// its own).
MergeReport MergeCharts(const TriMesh& mesh, const MergeOptions& options,
                        std::vector<uint32_t>* chart_of,
                        std::vector<ChartParam>* params = nullptr,
                        std::vector<uint8_t>* united = nullptr,
                        std::vector<double>* parts_scale = nullptr);

}  // namespace mebake::stream
