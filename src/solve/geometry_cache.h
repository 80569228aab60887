// The charts' sampled geometry pyramids in one memory-mapped file, with RAII pins and a
// residency budget (docs/architecture.md, Memory: pyramids live in a memory-mapped file;
// pinned charts stay resident, the rest is evicted under the budget).
//
// Every chart's pyramid (stream/geometry_image.h, 64 bytes per texel, all levels) is
// written once into an unlinked file under the bake directory, which is then mapped
// read-only (clean page-cache pages: dropping them costs no write). The solver reads it through
// GeometryPyramid views; a pass over a chart holds a GeometryPin. When a pin is released
// and the pinned-or-recently-used pyramids exceed the budget, the least recently used
// unpinned ones are dropped from this process (madvise MADV_DONTNEED on their pages; the
// bytes stay in the file and the page cache). Reading a dropped pyramid faults its pages
// back in: eviction changes speed and resident memory, never a value, so results are the
// same for any budget and thread count. Resident memory then follows the charts being
// worked on (about one per thread), not the chart count.
#pragma once

#include "stream/geometry_image.h"

#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

namespace mebake::solve {

class GeometryCache;

// Keeps one chart's pyramid resident while alive (a no-op for pyramids held in memory).
class GeometryPin {
public:
    GeometryPin() = default;
    GeometryPin(GeometryPin&& o) noexcept;
    GeometryPin& operator=(GeometryPin&& o) noexcept;
    GeometryPin(const GeometryPin&) = delete;
    GeometryPin& operator=(const GeometryPin&) = delete;
    ~GeometryPin();

private:
    friend class GeometryCache;
    GeometryPin(GeometryCache* cache, uint32_t chart) : cache_(cache), chart_(chart) {}
    GeometryCache* cache_ = nullptr;
    uint32_t chart_ = 0;
};

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
    GeometryCache* cache_ = nullptr;
    uint32_t chart_ = 0;
};

// stream::SampleBilinear on a view (both are stream::SampleBilinearOf: the same bits).
stream::SurfaceSample SampleBilinear(const GeometryPyramid& img, int level, float u, float v);

class GeometryCache {
public:
    // An unlinked file in directory `dir` (nothing is left behind, even after a crash).
    // budget_bytes: resident pyramids kept beyond the pinned ones. Throws Error(Io).
    GeometryCache(const std::string& dir, uint64_t budget_bytes);
    ~GeometryCache();
    GeometryCache(const GeometryCache&) = delete;
    GeometryCache& operator=(const GeometryCache&) = delete;

    // Appends a chart's pyramid (charts are numbered in the order added). Not
    // thread-safe; all Add() calls come before the first View(). Throws Error(Io) (a
    // full disk): callers can keep the pyramids in memory instead.
    uint32_t Add(const stream::GeometryImage& image);
    // The view of chart c (the first call maps the file); valid while the cache lives.
    GeometryPyramid View(uint32_t c);

    size_t chart_count() const { return entries_.size(); }
    uint64_t file_bytes() const { return size_; }
    uint64_t budget_bytes() const { return budget_; }

    struct Stats {
        uint64_t resident_bytes = 0;       // pyramids counted as resident now
        uint64_t peak_resident_bytes = 0;  // largest resident_bytes so far
        uint64_t evictions = 0;
        uint64_t pins = 0;
    };
    Stats stats() const;
    // Whether chart c is counted as resident (pinned or not yet evicted). For tests.
    bool resident(uint32_t c) const;

private:
    friend class GeometryPin;
    friend class GeometryPyramid;
    GeometryPin Pin(uint32_t c);
    void Unpin(uint32_t c);
    void TrimLocked();

    struct Entry {
        uint64_t offset = 0, bytes = 0;
        uint32_t resolution = 0;
        std::vector<size_t> level_sizes;  // texels per level, coarsest first
        uint32_t pins = 0;
        bool resident = false;
        uint64_t last_use = 0;
    };
    void DropPages(const Entry& e);

    std::string path_;  // for messages; the file itself is unlinked
    int fd_ = -1;
    uint8_t* data_ = nullptr;  // the read-only mapping, once View() made it
    uint64_t size_ = 0;
    uint64_t budget_ = 0;
    std::vector<Entry> entries_;
    mutable std::mutex mutex_;
    uint64_t clock_ = 0;
    Stats stats_;
};

}  // namespace mebake::solve
