// Turns one chart (a topological disc) into a Meshed Master Element parameterization:
// a near-isometric map with natural boundaries, placed in the unit square by a similarity.
// Method: a natural-boundary conformal map (BFF, bff.h, or LSCM, lscm.h), refined by
// local/global iterations (Liu et al. 2008, arap.h) towards area preservation, then
// rotating calipers + uniform scale into the square (square_fit.h).
// Master element background: the seed paper, section 3.1 step 3.
//
// Definitions used by the metrics (A_T = 3D area, a_T = uv area of triangle T, s = scale):
//   s          = sqrt(sum A_T / sum a_T), 3D length per uv unit, so that the unit square
//                stands for s^2 of surface and the mean area ratio is exactly 1.
//   r_T        = A_T / (s^2 a_T), the area ratio (Jacobian determinant relative to s^2).
//   deviation  = |r_T - 1| per triangle.
//   jacobian_deviation_mean = sum_T |A_T - s^2 a_T| / sum_T A_T: the fraction of the
//                surface's area the constant-Jacobian master element misplaces (the
//                uv-area-weighted mean of |r_T - 1|).
//   jacobian_deviation_p95  = 95th percentile of |r_T - 1| weighted by A_T.
//   jacobian_deviation_coarse = the same L1 measure after summing A_T and a_T per cell of
//                an 8 x 8 grid over the square (triangles binned by uv centroid): the
//                area misplaced at the scale of the lighting's quadtree nodes. Triangle-scale
//                noise of a scan inflates the per-triangle numbers but cancels here, and
//                splitting a chart cannot remove it, so the split test uses this one.
//   conformal ratio = sigma1 / sigma2 >= 1 of the triangle's Jacobian (1 = no shear).
//
// Measured (CPU seconds, one core; default options; "shear" = conformal_mean):
//   chart                 vertices  BFF alone  total  dev mean  coarse  shear  virtual
//   bumpy height field      10K       0.04     0.11    0.84%    0.01%   1.08    0.16
//   bumpy height field      50K       0.37     0.94    0.84%    0.00%   1.08    0.16
//   bumpy height field     100K       0.80     1.91    0.84%    0.00%   1.08    0.16
//   85-degree cap          100K       0.64     1.91    2.2%     1.9%    1.32    0.26
// LSCM instead of BFF costs 0.13 s / 1.18 s at 10K / 50K and starts worse (bumpy: 67%
// deviation before refinement instead of 6%, and 1.3x the shear after it).
// Real scan charts (nefertiti, lucy; region growing under normal cones of 20-70 degrees,
// 500-27K triangles): dev mean 0.04-0.9%, coarse <= 0.12%. So the seed's 1% threshold,
// applied to the coarse deviation, splits hemisphere-like charts (caps beyond ~80
// degrees), not charts that are merely noisy or strongly curved in one direction.
#pragma once

#include "core/vec.h"
#include "stream/arap.h"
#include "stream/square_fit.h"
#include "stream/trimesh.h"

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace mebake::stream {

enum class ParamStatus {
    kOk,
    // The input is not a valid disc; uv is empty. The caller splits or discards the chart.
    kEmpty,         // no triangles
    kBadIndex,      // a triangle names a vertex that does not exist, or one vertex twice
    kNonFinite,     // a position is NaN or infinite
    kNonManifold,   // an edge with > 2 triangles, inconsistent orientation, or a pinched vertex
    kNotDisc,       // several components, unreferenced vertices, no boundary (closed),
                    // several boundary loops, or handles (Euler characteristic != 1)
    kDegenerate,    // zero total area
    kSolverFailed,  // the sparse factorization failed
    // A parameterization was computed (uv, metrics filled) but the chart should be split.
    kFlipped,    // some uv triangles are flipped or degenerate
    kOverlap,    // no flips, but the map is not one-to-one: parts of the chart overlap in uv
    kDistorted,  // jacobian_deviation_coarse above ParamOptions::max_jacobian_deviation
};

const char* ParamStatusName(ParamStatus status);
// A map is one-to-one enough when at most kMaxOverlap of its points are covered twice,
// tested on a grid of kOverlapResolution points a side (the largest merged chart's
// light-map resolution, chart_builder.h). Scan noise at a chart's border makes thin
// overlaps that hold a few texels; a wrapped chart holds whole regions twice.
inline constexpr uint32_t kOverlapResolution = 512;
inline constexpr double kMaxOverlap = 0.01;

// The fraction of the covered points of a res x res grid of centres over the square that
// lie strictly inside more than one uv triangle.
double UvOverlapFraction(std::span<const std::array<uint32_t, 3>> triangles,
                         std::span<const Vec2f> uv, uint32_t res);

// True when uv, scale and metrics are filled in (kOk, kFlipped, kOverlap, kDistorted).
inline bool HasUv(ParamStatus s) {
    return s == ParamStatus::kOk || s == ParamStatus::kFlipped || s == ParamStatus::kOverlap ||
           s == ParamStatus::kDistorted;
}

enum class ParamInit {
    kBff,   // Boundary First Flattening (bff.h): one interior-Laplacian factorization
    kLscm,  // LSCM (lscm.h): a coupled system twice the size, ~5-10x slower to factorize
};

struct ParamOptions {
    ParamInit init = ParamInit::kBff;  // falls back to LSCM if BFF fails or folds
    bool refine = true;                // local/global refinement (arap.h)
    ArapOptions refine_options;
    double margin = 1.0 / 64;  // free band around the chart in the square
    SquareFitObjective objective = SquareFitObjective::kMinLongerSide;
    // Split threshold on jacobian_deviation_coarse (see the header comment); the seed paper
    // used 1% on its Jacobian deviation.
    double max_jacobian_deviation = 0.01;
};

struct ParamMetrics {
    ParamInit init = ParamInit::kBff;  // the initial flattening actually used
    uint32_t init_flipped = 0;         // flipped triangles of the initial flattening
    int refine_iterations = 0;
    bool refine_stopped_by_flip = false;
    uint32_t flipped = 0;  // uv triangles not strictly counter-clockwise (final float uv)
    double area_3d = 0;
    double jacobian_deviation_mean = 0;
    double jacobian_deviation_p95 = 0;
    double jacobian_deviation_max = 0;  // over triangles with 3D area > 0
    double jacobian_deviation_coarse = 0;
    double conformal_mean = 1;  // 3D-area-weighted mean of sigma1 / sigma2
    double conformal_max = 1;
    double virtual_fraction = 1;  // 1 - uv area of the chart
};

struct ChartParam {
    ParamStatus status = ParamStatus::kEmpty;
    std::string message;            // why, when status is not kOk
    std::vector<Vec2f> uv;          // per vertex, in [0,1]^2
    double scale = 0;               // s: 3D length per uv unit
    std::vector<float> area_ratio;  // per triangle r_T; 0 where the uv triangle is flipped
                                    // or has zero area
    ParamMetrics metrics;
};

// Checks the disc precondition: indices in range, edge- and vertex-manifold, consistently
// oriented, connected, every vertex used, exactly one boundary loop, Euler characteristic
// 1. On success returns kOk and the boundary loop (vertex indices, in the triangles'
// winding order); otherwise the status and a message.
struct DiscCheck {
    ParamStatus status = ParamStatus::kOk;
    std::string message;
    std::vector<uint32_t> boundary;
};
DiscCheck CheckDisc(uint32_t vertex_count, std::span<const std::array<uint32_t, 3>> triangles);

// Per-triangle area ratios and the summary metrics of a uv map (see the header comment).
// Fills scale, area_ratio and metrics (except the LSCM/ARAP counters) of *out.
void MeasureDistortion(std::span<const Vec3f> position,
                       std::span<const std::array<uint32_t, 3>> triangles,
                       std::span<const Vec2f> uv, ChartParam* out);

// The whole pipeline: FlattenChart, then ClassifyChart when a map was computed.
// Deterministic: the same input gives the same bytes.
ChartParam ParameterizeChart(const TriMesh& chart, const ParamOptions& options = {});

// Its two halves, for a caller with tests of its own to make before the costlier split
// tests (chart_merge.cpp). FlattenChart computes uv, scale, area ratios and metrics
// (flipped included) and leaves status kOk, or returns the reason there is no map;
// ClassifyChart then sets kFlipped, kOverlap or kDistorted where the chart must be split.
ChartParam FlattenChart(const TriMesh& chart, const ParamOptions& options = {});
void ClassifyChart(const TriMesh& chart, const ParamOptions& options, ChartParam* param);

}  // namespace mebake::stream
