// Light-map and E-map texels on both sides of every chart seam, solved so that a viewer's
// bilinear filtering shows one value at any point of the seam (issue 14, item 3b).
//
// The stitched field (seam_stitch.h) is continuous across chart borders, but a map stores
// it as point samples at texel centres of each chart's own grid, and a viewer filters each
// side bilinearly from its own texels: the two sides then agree only up to the
// interpolation error, and texels of the virtual part (never seen on their own) take part.
// As game light mappers do (M. Iwanicki, "Lighting technology of The Last of Us", SIGGRAPH
// 2013 Advances in Real-Time Rendering: least squares over the seam's bilinear samples; S. Liu,
// Z. Ferguson, A. Jacobson, Y. Gingold, "Seamless: seam erasure and seam-aware decoupling of
// shape from mesh resolution", ACM TOG 36(6), 2017, the same energy for texture atlases),
// the texels whose bilinear footprint touches a seam are the unknowns x, and
//   minimize  lambda sum_samples (bilinear_A(x, p_A) - bilinear_B(x, p_B))^2 + |x - x0|^2
// with x0 the texels as shaded and samples at three points per texel along every seam
// edge (p_A, p_B the same surface point in both charts). The normal equations
// (I + lambda A^T A) x = x0 are solved per channel by conjugate gradients with a Jacobi
// preconditioner, A applied as a sparse operator (8 entries per sample), never formed:
// memory grows with the seams' texels, not with the map (per texel 4 bytes of index, its
// channels as floats and 5 doubles of CG; the samples, 64 bytes each, in a temporary file
// read in order a block at a time behind a 4 MiB page cache; the sides
// waiting for their pair only while a neighbouring chart can still come, seam_graph.h's
// BorderPairing). The global CG is kept (one system, not one per seam component) so the
// texels are the same bytes as before. Single-threaded and
// in chart order: the same texels for any thread count. Folds (faces more than 45 degrees
// apart) and mesh borders are left alone, as seam_graph.h does.
#pragma once

#include "output/atlas.h"
#include "output/bake_view.h"
#include "output/lightmap.h"

#include <cstdint>
#include <vector>

namespace mebake::output {

struct TexelStitchStats {
    uint64_t texels = 0;    // unknowns
    uint64_t samples = 0;   // seam samples (rows of A)
    int iterations = 0;     // most CG iterations over the channels
    double rms_before = 0;  // bilinear mismatch over all samples and channels
    double rms_after = 0;
};

class TexelStitch {
public:
    // The stitched texel (i, j) of chart c's square (MapChannels floats), or nullptr.
    const float* Find(uint32_t chart, uint32_t i, uint32_t j) const;
    size_t size() const { return first_.empty() ? 0 : first_.back(); }

private:
    friend TexelStitch StitchTexels(const BakeView&, const Atlas&, MapContent, TexelStitchStats*);
    // Texel j * res + i of a chart: its index among the chart's seam texels, or -1; its
    // slot among all charts' (the unknown's index), or -1.
    int64_t Local(uint32_t chart, uint32_t texel) const;
    int64_t Slot(uint32_t chart, uint32_t texel) const;
    // A chart's seam texels. Kept per chart, each array its exact size: one array for all
    // would grow by doubling while the charts come in, up to three times the texels' bytes
    // at a reallocation (51 MB at 100M triangles) in the middle of the stitch's preparation.
    struct ChartTexels {
        std::vector<uint32_t> texel;  // j * res + i, ascending
        std::vector<float> values;    // channels_ per texel
    };
    int channels_ = 0;
    std::vector<uint32_t> resolution_;  // per chart
    std::vector<uint32_t> first_;       // per chart and one more: its first slot
    std::vector<ChartTexels> charts_;   // per chart
};

// The weight lambda of the seam samples against keeping a texel as shaded.
constexpr double kSeamWeight = 100;

TexelStitch StitchTexels(const BakeView& view, const Atlas& atlas, MapContent content,
                         TexelStitchStats* stats = nullptr);

}  // namespace mebake::output
