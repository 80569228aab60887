// Light maps and vector irradiance maps (seed paper 000, "Display": "we simply generate
// light-maps, by computing in each parameter space B(x) = rho(x) (n_x . E(x))+"; for
// glossy display "three textures store the three components (x, y, z) in R, G, B").
//
// Every texel of a chart's square is shaded at its centre with the tile's full-resolution
// normal and albedo (bake_view.h ChartShader::AtUv); the texels a viewer's bilinear filter
// reads along chart seams are then solved to agree across them (texel_stitch.h, when the
// view is stitched); gutter texels repeat the nearest border texel; texels outside every
// chart are 0. Pages are computed shelf by shelf, a
// group of charts (two per thread) at a time, and handed out in bands of rows, so memory
// holds one shelf's rows and one group's tiles, not a page nor a whole shelf's tiles.
//
// Contents:
//   Radiosity   channels R, G, B = B in W/m^2 (linear, >= 0) and A = 1 on chart blocks
//               (gutters included), 0 on unused texels.
//   Irradiance  channels E.x.R, E.x.G, E.x.B, E.y.R, ..., E.z.B = the x, y, z world-space
//               components of the vector irradiance E per colour (W/m^2, signed); all 0 for
//               a radiosity solution.
// A PNG light map holds the radiance B/pi tone-mapped (tonemap.h), the same mapping
// `mebake render` uses, so a viewer showing it as emission matches the rendered views.
#pragma once

#include "io/exr_writer.h"
#include "output/atlas.h"
#include "output/bake_view.h"
#include "output/tonemap.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace mebake::output {

enum class MapContent { Radiosity, Irradiance };

class TexelStitch;
struct StitchedTexels;

int MapChannels(MapContent content);
std::vector<std::string> MapChannelNames(MapContent content);

// Receives rows [first_row, first_row + rows) of a page, pixel-major, MapChannels floats
// per texel, top to bottom with no gaps.
using PageSink =
    std::function<void(std::span<const float> pixels, uint32_t first_row, uint32_t rows)>;

// Computes one page and streams it to `sink` in bands of at most band_rows rows, holding
// the tiles of `group` charts at a time (0: two per thread). Texels `stitch` has are taken
// from it (nullptr: every texel as shaded).
void ComputePage(const BakeView& view, const Atlas& atlas, uint32_t page, MapContent content,
                 const PageSink& sink, uint32_t band_rows = 64, size_t group = 0,
                 const TexelStitch* stitch = nullptr);

// The map value of chart point uv (MapChannels floats): B and A = 1, or E.
void ShadeTexel(const ChartShader& shader, Vec2f uv, MapContent content, float* out);

// Fills block rows [row_begin, row_end) of one chart's block (gutters included): `out`
// points at texel (0, row_begin) of the block, rows `stride` floats apart, MapChannels
// floats per texel; texels `stitch` (this chart's, TexelStitch::Chart) has are taken from
// it. Exposed for tests.
void FillChartBlock(const ChartShader& shader, const Atlas& atlas, uint32_t chart,
                    MapContent content, uint32_t row_begin, uint32_t row_end, float* out,
                    size_t stride, const StitchedTexels* stitch = nullptr);

// The file of page p: `path` itself for a one-page atlas, else UDIM-numbered
// "name.<1001 + p>.ext" (page p = UDIM tile 1001 + p: u offset p % 10, v offset p / 10).
std::string PagePath(const std::string& path, uint32_t page, uint32_t pages);
// The extension of `path` in lower case (".exr"; empty when it has none).
std::string Extension(const std::string& path);

struct MapWriteOptions {
    io::ExrPixelType exr_type = io::ExrPixelType::Half;
    io::ExrCompression compression = io::ExrCompression::Zip;
    ToneMap tone;  // PNG only
    // A Radiosity .exr map also written as PNG to this path (PagePath per page) from the
    // same shaded texels: one shading and one stitch for both (the bake's light map).
    std::string png_path;
    // The texel stitch's share (MemoryBudget::StitchRows: samples in memory, channels in
    // parallel); it changes the time, not the texels.
    uint64_t stitch_memory = MemoryBudget(uint64_t(1) << 30).StitchRows();
};

// Writes every page to PagePath(path, ...), as OpenEXR (".exr") or, for Radiosity, 8-bit
// sRGB PNG (".png"), with the seams' texels stitched when the view is. Returns the paths
// written (options.png_path's pages after the main ones). Throws Error(Usage) for another
// extension, or for "-" with more than one page.
std::vector<std::string> WriteMapPages(const BakeView& view, const Atlas& atlas,
                                       const std::string& path, MapContent content,
                                       const MapWriteOptions& options);

// The tone-mapped light map of one page as an encoded PNG (for embedding in a .glb), with
// `stitch`'s texels (StitchTexels for MapContent::Radiosity; nullptr: as shaded).
std::vector<uint8_t> EncodeLightMapPng(const BakeView& view, const Atlas& atlas, uint32_t page,
                                       const ToneMap& tone, const TexelStitch* stitch = nullptr);

// The texel stitch of `content` for this view, or nullptr when the view is not stitched.
std::unique_ptr<TexelStitch> StitchForView(
    const BakeView& view, const Atlas& atlas, MapContent content,
    uint64_t memory_bytes = MemoryBudget(uint64_t(1) << 30).StitchRows());

}  // namespace mebake::output
