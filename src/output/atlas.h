// The light-map atlas: every chart's square (its `resolution` texels per side, a power of
// two) plus a gutter of `gutter` texels on each side, shelf-packed onto one or more pages
// (the "next-fit decreasing height" shelf algorithm; Coffman et al. 1980). Each gutter
// repeats its chart's border texels, so bilinear filtering at a chart's edge never reads
// a neighbour.
//
// Deterministic: charts are placed by decreasing block size, ties by chart id. A page is
// at most `max_size` texels per side. Its width is chosen among candidates (powers of two,
// or with power_of_two = false the multiples of 4 that hold a whole number of the largest
// blocks) as the one giving the smallest page that takes all remaining charts; its height
// is then the smallest power of two (or multiple of 4) that holds them. When no page takes
// them all, a full max_size page is filled and packing goes on with the next one.
// Power-of-two chart squares plus gutters fit power-of-two pages poorly (8 charts of 512
// fill a 2048 page to 50%, a 1548 one to 88%): power_of_two = false trades mipmap-friendly
// sizes for that space.
//
// Coordinates: texel (x, y) of a page, y counted from the image's top row (the first row
// written to EXR/PNG). A chart's texel (i, j) of its square (i along u, j along v) is
// page texel (x0 + gutter + i, y0 + gutter + j). The atlas uv of chart point (u, v) is
//   ((x0 + gutter + u * res) / page_width, (y0 + gutter + v * res) / page_height),
// the glTF / Direct3D convention (origin at the image's top-left). Formats whose uv origin
// is the bottom-left (OBJ, PLY as read by most tools) use (s, 1 - t): see export_mesh.h.
#pragma once

#include "core/vec.h"

#include <cstdint>
#include <span>
#include <vector>

namespace mebake::output {

struct AtlasOptions {
    uint32_t max_size = 8192;  // largest page side, texels
    uint32_t gutter = 2;       // texels on each side of a chart's square
    bool power_of_two = true;  // page sides powers of two (else multiples of 4)
};

struct AtlasChart {
    uint32_t page = 0;
    uint32_t x = 0, y = 0;    // top-left texel of the block (gutter included)
    uint32_t resolution = 0;  // texels per side of the chart's square
};

struct AtlasShelf {
    uint32_t y = 0, height = 0;    // rows [y, y + height) of the page
    std::vector<uint32_t> charts;  // left to right
};

struct AtlasPage {
    uint32_t width = 0, height = 0;
    std::vector<AtlasShelf> shelves;  // top to bottom
};

struct Atlas {
    uint32_t gutter = 0;
    std::vector<AtlasPage> pages;
    std::vector<AtlasChart> charts;  // by chart id

    uint32_t block(uint32_t chart) const { return charts[chart].resolution + 2 * gutter; }
    // Atlas uv of chart point uv (see above).
    Vec2f AtlasUv(uint32_t chart, Vec2f uv) const;
    // The chart point at the centre of block texel (bx, by) (0 <= bx, by < block): texels of
    // the gutter map to the nearest border texel's centre.
    Vec2f TexelUv(uint32_t chart, uint32_t bx, uint32_t by) const;
    // Texels of all pages, and the share of them that chart squares (without gutters) fill.
    uint64_t texels() const;
    double fill() const;
};

// Packs charts of the given resolutions (index = chart id). Throws Error(Usage) when a
// chart's block does not fit in max_size, or when max_size is not a power of two >= 16.
Atlas PackAtlas(std::span<const uint32_t> resolutions, const AtlasOptions& options = {});

}  // namespace mebake::output
