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
// memory grows with the seams' texels, not with the map: 5 doubles of CG per texel while
// the CG runs (13 when the three colour channels are solved in parallel, below). The
// samples, 64 bytes each, stay in memory up to the `export.stitch_rows` share (every CG
// pass reads them all); past it they go to a temporary file read in order a block at a
// time behind a 4 MiB page cache. The texels' indices and values are in two more files
// (256 KiB cached each), written as each chart is prepared, read and written in slot
// order by the CG and read back a chart at a time with its tile by the light map
// (TexelStitch::Chart): a chart's texel list stays in memory only while a later chart can
// pair with it, as its sides wait for their pair (seam_graph.h's BorderPairing), so no
// per-texel array of the whole map outlives the CG (it was 17 MB at 100M triangles, 858K
// seam texels). The global CG is kept (one system, not one per seam component) so the
// texels are the same bytes as before. Each channel's CG is single-threaded and in chart
// order; the channels run in parallel when the samples and their vectors fit the share
// (they share nothing else): the same texels for any thread count. Folds (faces more than 45 degrees
// apart) and mesh borders are left alone, as seam_graph.h does.
#pragma once

#include "output/atlas.h"
#include "output/bake_view.h"
#include "output/lightmap.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace mebake::output {

struct TexelStitchStats {
    uint64_t texels = 0;    // unknowns
    uint64_t samples = 0;   // seam samples (rows of A)
    int iterations = 0;     // most CG iterations over the channels
    double rms_before = 0;  // bilinear mismatch over all samples and channels
    double rms_after = 0;
    bool rows_in_memory = true;         // else in a temporary file
    bool channels_in_parallel = false;  // else solved in turn
};

// One chart's stitched texels, read back from the stitch's file for the chart being shaded.
struct StitchedTexels {
    std::vector<uint32_t> texel;  // j * res + i, ascending
    std::vector<float> values;    // channels per texel
    // Texel `texel`'s `channels` floats, or nullptr when it is not a seam texel.
    const float* Find(uint32_t texel, int channels) const;
};

class TexelStitch {
public:
    TexelStitch();
    ~TexelStitch();
    TexelStitch(TexelStitch&&) noexcept;
    // Chart c's stitched texels (empty when it has none). Thread-safe.
    StitchedTexels Chart(uint32_t c) const;
    size_t size() const { return first_.empty() ? 0 : first_.back(); }

private:
    friend TexelStitch StitchTexels(const BakeView&, const Atlas&, MapContent, TexelStitchStats*,
                                    uint64_t);
    struct Files;  // every chart's texels and values, in slot order, in temporary files
    int channels_ = 0;
    std::vector<uint32_t> first_;  // per chart and one more: its first slot
    std::unique_ptr<Files> files_;
};

// The weight lambda of the seam samples against keeping a texel as shaded.
constexpr double kSeamWeight = 100;

// `memory_bytes` (the export's `export.stitch_rows` share) holds the seam samples in memory
// while they fit, and lets the colour channels' CGs run in parallel when their vectors fit
// too; past it the samples go to a temporary file and the channels are solved in turn. It
// changes the time and memory, never the texels.
TexelStitch StitchTexels(const BakeView& view, const Atlas& atlas, MapContent content,
                         TexelStitchStats* stats = nullptr,
                         uint64_t memory_bytes = MemoryBudget(uint64_t(1) << 30).StitchRows());

}  // namespace mebake::output
