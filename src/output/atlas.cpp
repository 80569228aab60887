#include "output/atlas.h"

#include "core/check.h"
#include "core/error.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace mebake::output {

namespace {

uint32_t NextPow2(uint64_t n) {
    uint64_t p = 1;
    while (p < n)
        p <<= 1;
    return uint32_t(p);
}

uint32_t RoundUp4(uint64_t n) {
    return uint32_t((n + 3) & ~uint64_t(3));
}

struct Placement {
    uint32_t x, y;
};

// Next-fit shelf packing of blocks[order[first..]] into a width x height page. Returns how
// many fit (a prefix) and the rows used; fills `out` when non-null.
size_t Simulate(std::span<const uint32_t> order, size_t first, std::span<const uint32_t> blocks,
                uint32_t width, uint32_t height, uint32_t* used_height,
                std::vector<Placement>* out) {
    uint64_t x = 0, y = 0, shelf = 0;
    size_t k = first;
    for (; k < order.size(); ++k) {
        const uint32_t b = blocks[order[k]];
        if (b > width)
            break;
        if (x + b > width) {
            y += shelf;
            x = 0;
            shelf = 0;
        }
        if (y + b > height)
            break;
        if (out)
            out->push_back({uint32_t(x), uint32_t(y)});
        x += b;
        shelf = std::max<uint64_t>(shelf, b);
    }
    *used_height = uint32_t(y + shelf);
    return k - first;
}

}  // namespace

Vec2f Atlas::AtlasUv(uint32_t chart, Vec2f uv) const {
    const AtlasChart& c = charts[chart];
    const AtlasPage& p = pages[c.page];
    return Vec2f(float((double(c.x) + gutter + double(uv.x) * c.resolution) / p.width),
                 float((double(c.y) + gutter + double(uv.y) * c.resolution) / p.height));
}

Vec2f Atlas::TexelUv(uint32_t chart, uint32_t bx, uint32_t by) const {
    const uint32_t res = charts[chart].resolution;
    const int64_t i = std::clamp<int64_t>(int64_t(bx) - gutter, 0, int64_t(res) - 1);
    const int64_t j = std::clamp<int64_t>(int64_t(by) - gutter, 0, int64_t(res) - 1);
    return Vec2f(float((double(i) + 0.5) / res), float((double(j) + 0.5) / res));
}

uint64_t Atlas::texels() const {
    uint64_t n = 0;
    for (const auto& p : pages)
        n += uint64_t(p.width) * p.height;
    return n;
}

double Atlas::fill() const {
    uint64_t used = 0;
    for (const auto& c : charts)
        used += uint64_t(c.resolution) * c.resolution;
    const uint64_t all = texels();
    return all ? double(used) / double(all) : 0.0;
}

Atlas PackAtlas(std::span<const uint32_t> resolutions, const AtlasOptions& opt) {
    if (opt.max_size < 16 || opt.max_size > (1u << 16) || (opt.max_size & (opt.max_size - 1)))
        UsageError("--max-atlas {}: expected a power of two from 16 to 65536", opt.max_size);
    if (opt.gutter > 64)
        UsageError("gutter {}: at most 64 texels", opt.gutter);
    Atlas atlas;
    atlas.gutter = opt.gutter;
    const size_t n = resolutions.size();
    atlas.charts.resize(n);
    std::vector<uint32_t> blocks(n);
    for (size_t c = 0; c < n; ++c) {
        CHECK_GE(resolutions[c], 1u);
        const uint64_t b = uint64_t(resolutions[c]) + 2 * uint64_t(opt.gutter);
        if (b > opt.max_size)
            UsageError("chart {} needs {} x {} texels with its gutters, more than --max-atlas {}",
                       c, b, b, opt.max_size);
        blocks[c] = uint32_t(b);
        atlas.charts[c].resolution = resolutions[c];
    }
    std::vector<uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(),
                     [&](uint32_t a, uint32_t b) { return blocks[a] > blocks[b]; });

    std::vector<Placement> placed;
    size_t first = 0;
    while (first < n) {
        // The smallest page that takes every remaining chart, if one of at most max_size
        // per side does; otherwise a full max_size page.
        uint64_t area = 0;
        for (size_t k = first; k < n; ++k)
            area += uint64_t(blocks[order[k]]) * blocks[order[k]];
        uint32_t best_w = 0, best_h = 0;
        const uint32_t largest = blocks[order[first]];
        std::vector<uint32_t> widths;
        if (opt.power_of_two) {
            for (uint32_t w = NextPow2(largest); w <= opt.max_size; w *= 2)
                widths.push_back(w);
        } else {
            // Widths holding k of the largest blocks per shelf, from a little under the
            // square root of the area on (narrower pages cannot be smaller); 64 at most.
            const uint64_t k0 =
                std::max<uint64_t>(1, uint64_t(0.7 * std::sqrt(double(area)) / largest));
            for (uint64_t k = k0; k < k0 + 64 && RoundUp4(k * largest) <= opt.max_size; ++k)
                widths.push_back(RoundUp4(k * largest));
            if (widths.empty() || widths.back() != opt.max_size)
                widths.push_back(opt.max_size);
        }
        for (uint32_t w : widths) {
            if (uint64_t(w) * opt.max_size < area)
                continue;
            uint32_t used = 0;
            if (Simulate(order, first, blocks, w, opt.max_size, &used, nullptr) != n - first)
                continue;
            const uint32_t h = opt.power_of_two ? NextPow2(used) : RoundUp4(used);
            const uint64_t a = uint64_t(w) * h, best = uint64_t(best_w) * best_h;
            if (best_w == 0 || a < best || (a == best && std::max(w, h) < std::max(best_w, best_h)))
                best_w = w, best_h = h;
        }
        if (best_w == 0)
            best_w = best_h = opt.max_size;
        placed.clear();
        uint32_t used = 0;
        const size_t k = Simulate(order, first, blocks, best_w, best_h, &used, &placed);
        CHECK_GT(k, 0u);
        AtlasPage page;
        page.width = best_w;
        page.height = best_h;
        const uint32_t page_index = uint32_t(atlas.pages.size());
        for (size_t i = 0; i < k; ++i) {
            const uint32_t c = order[first + i];
            atlas.charts[c].page = page_index;
            atlas.charts[c].x = placed[i].x;
            atlas.charts[c].y = placed[i].y;
            if (page.shelves.empty() || page.shelves.back().y != placed[i].y)
                page.shelves.push_back({placed[i].y, blocks[c], {}});
            page.shelves.back().charts.push_back(c);
        }
        atlas.pages.push_back(std::move(page));
        first += k;
    }
    return atlas;
}

}  // namespace mebake::output
