// Segmentation of a repaired brick into charts that are topological discs (Master-Element
// paper, section 3.1 step 2): discrete Lloyd iterations in the spirit of Sander et al. 2003
// and variational shape approximation (Cohen-Steiner, Alliez, Desbrun 2004, L2,1 metric
// with normal proxies), with a compactness term so charts fill a square well.
#pragma once

#include "stream/topology.h"
#include "stream/trimesh.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mebake::stream {

struct SegmentOptions {
    // Initial number of charts of a component = ceil(faces / target_chart_faces).
    uint32_t target_chart_faces = 30000;
    // Hard bound: a chart never has more vertices than this.
    uint32_t max_chart_vertices = 50000;
    // Near-developable bound: 95% of a chart's area has its (lightly smoothed) normal within
    // this angle of the chart's mean normal; charts over it get another seed.
    double max_normal_deviation_deg = 60.0;
    // Weight of the distance term against the normal term (0 = pure VSA L2,1).
    double compactness = 0.5;
    int lloyd_iterations = 6;       // before the first check of the bounds
    int refinement_rounds = 12;     // seed insertions (each followed by 3 iterations)
    uint32_t min_chart_faces = 64;  // smaller charts are merged into a neighbour if possible
};

struct SegmentReport {
    size_t components = 0;  // edge-connected parts of the mesh
    size_t initial_seeds = 0;
    size_t inserted_seeds = 0;  // for normal deviation or size
    size_t lloyd_iterations = 0;
    size_t leftover_charts = 0;  // final charts started where no seed could grow to
    size_t merged_charts = 0;    // small charts merged into a neighbour
    size_t split_charts = 0;     // charts split after the Lloyd stage (size or topology)
    size_t charts = 0;
    size_t max_chart_faces = 0;
    size_t max_chart_vertices = 0;
    double max_normal_deviation_deg = 0;  // largest 95%-area deviation over the charts
};

// Chart id per triangle, ids 0..charts-1 numbered by each chart's smallest triangle index.
// Every chart is a topological disc (CheckDisc(ExtractChart(...)).IsDisc()) when the mesh
// is an oriented manifold (Repair's output); on other input each chart is still a disc in
// the sense of its face-edge complex. Deterministic; single-threaded per call. Throws a
// usage Error on invalid options.
std::vector<uint32_t> SegmentCharts(const TriMesh& mesh, const SegmentOptions& options,
                                    SegmentReport* report = nullptr);

// Splits one chart (a disc, typically from ExtractChart) into discs by Lloyd iterations
// from `parts` seeds placed by farthest-point sampling. Returns a part id per triangle,
// numbered by smallest triangle index; normally exactly `parts` parts, fewer if the chart
// has fewer triangles, occasionally more where a disc could not grow around an obstacle.
std::vector<uint32_t> SplitChart(const TriMesh& chart, int parts);

// The triangles of one chart as a mesh of its own: vertices in increasing order of their
// index in `mesh`, triangles in mesh order; global ids, albedo and materials carried over.
TriMesh ExtractChart(const TriMesh& mesh, const std::vector<uint32_t>& chart_of_tri,
                     uint32_t chart);

// All charts at once (chart c at index c), in O(F log F) rather than O(F) per chart.
std::vector<TriMesh> ExtractCharts(const TriMesh& mesh, const std::vector<uint32_t>& chart_of_tri);

// Boundary loops, Euler characteristic, manifoldness; IsDisc() tells if m is a disc.
TopologyReport CheckDisc(const TriMesh& m);

}  // namespace mebake::stream
