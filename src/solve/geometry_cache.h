// The charts' sampled geometry pyramids (stream/geometry_image.h, 64 bytes per texel, all
// levels), one region per chart of a core/mapped_cache.h file: the solver reads them
// through GeometryPyramid views, a pass over a chart holds its pin, and the least recently
// used unpinned pyramids are dropped beyond the budget (docs/architecture.md, Memory).
// Eviction never changes a value, so results are the same for any budget and thread count.
#pragma once

#include "core/mapped_cache.h"
#include "stream/geometry_image.h"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace mebake::solve {

class GeometryCache;

// Keeps one chart's pyramid resident while alive (holds nothing for in-memory pyramids).
using GeometryPin = RegionPin;

// A read-only view of one chart's pyramid with stream::GeometryImage's interface. Either
// owns an in-memory image (tests, small scenes) or points into a GeometryCache.
class GeometryPyramid {
public:
    GeometryPyramid() = default;
    explicit GeometryPyramid(stream::GeometryImage image);

    uint32_t resolution = 0;
    // levels[l] has (2^l)^2 texels, row-major; levels.back() is the finest.
    std::vector<std::span<const stream::GeometryTexel>> levels;

    int finest_level() const { return int(levels.size()) - 1; }
    const stream::GeometryTexel& At(int level, uint32_t i, uint32_t j) const {
        return levels[size_t(level)][size_t(j) * (size_t(1) << level) + i];
    }
    // Hold while reading the pyramid (one pass over a chart).
    GeometryPin Pin() const;

private:
    friend class GeometryCache;
    std::shared_ptr<const stream::GeometryImage> owned_;
    MappedCache* cache_ = nullptr;
    uint32_t chart_ = 0;
};

// stream::SampleBilinear on a view (both are stream::SampleBilinearOf: the same bits).
stream::SurfaceSample SampleBilinear(const GeometryPyramid& img, int level, float u, float v);

class GeometryCache {
public:
    // An unlinked file in directory `dir`; budget_bytes: resident pyramids kept beyond the
    // pinned ones. Throws Error(Io).
    GeometryCache(const std::string& dir, uint64_t budget_bytes);

    // Appends a chart's pyramid (charts are numbered in the order added). Not
    // thread-safe; all Add() calls come before the first View(). Throws Error(Io) (a
    // full disk): callers can keep the pyramids in memory instead.
    uint32_t Add(const stream::GeometryImage& image);
    // The view of chart c (the first call maps the file); valid while the cache lives.
    GeometryPyramid View(uint32_t c);

    size_t chart_count() const { return charts_.size(); }
    uint64_t file_bytes() const { return regions_.file_bytes(); }
    uint64_t budget_bytes() const { return regions_.budget_bytes(); }

    using Stats = MappedCache::Stats;
    Stats stats() const { return regions_.stats(); }
    // Whether chart c is counted as resident (pinned or not yet evicted). For tests.
    bool resident(uint32_t c) const { return regions_.resident(c); }

private:
    struct Chart {
        uint32_t resolution = 0;
        std::vector<size_t> level_sizes;  // texels per level, coarsest first
    };
    MappedCache regions_;  // region c is chart c's pyramid
    std::vector<Chart> charts_;
};

}  // namespace mebake::solve
