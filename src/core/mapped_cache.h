// Regions of one unlinked file, memory-mapped, with RAII pins and a residency budget: the
// cache for data that is read a region at a time (the solve's geometry pyramids, one per
// chart). Its sibling for data looked up element by element is core/paged_file.h.
//
// Regions are appended once (each starts on a page boundary), then the file is mapped
// read-only: its pages are clean page-cache pages, so dropping them costs no write. A pass
// over a region holds a RegionPin. When a pin is released and the pinned or recently used
// regions exceed the budget, the least recently used unpinned ones are dropped from this
// process (madvise MADV_DONTNEED; the bytes stay in the file and the kernel's page cache).
// Reading a dropped region faults its pages back in: eviction changes speed and resident
// memory, never a value, so results are the same for any budget and thread count, and
// resident memory follows the regions being worked on, not the number of regions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <mutex>
#include <span>
#include <string>
#include <vector>

namespace mebake {

class MappedCache;

// Keeps one region resident while alive (a default-constructed pin holds nothing).
class RegionPin {
public:
    RegionPin() = default;
    RegionPin(RegionPin&& o) noexcept;
    RegionPin& operator=(RegionPin&& o) noexcept;
    RegionPin(const RegionPin&) = delete;
    RegionPin& operator=(const RegionPin&) = delete;
    ~RegionPin();

private:
    friend class MappedCache;
    RegionPin(MappedCache* cache, uint32_t region) : cache_(cache), region_(region) {}
    MappedCache* cache_ = nullptr;
    uint32_t region_ = 0;
};

class MappedCache {
public:
    // An unlinked file in directory `dir` (nothing is left behind, even after a crash);
    // `what` names it in messages. budget_bytes: resident regions kept beyond the pinned
    // ones. Throws Error(Io).
    MappedCache(const std::string& dir, const std::string& what, uint64_t budget_bytes);
    ~MappedCache();
    MappedCache(const MappedCache&) = delete;
    MappedCache& operator=(const MappedCache&) = delete;

    // Appends a region made of `pieces`, in order (regions are numbered in the order
    // added). Not thread-safe; every Add() comes before the first Data(). Throws Error(Io)
    // (a full disk): callers can keep their data in memory instead.
    uint32_t Add(std::span<const std::span<const std::byte>> pieces);
    // The bytes of region r (the first call maps the file); valid while the cache lives.
    // Read them while holding a pin.
    const std::byte* Data(uint32_t r);
    RegionPin Pin(uint32_t r);

    size_t region_count() const { return regions_.size(); }
    uint64_t region_bytes(uint32_t r) const { return regions_[r].bytes; }
    uint64_t file_bytes() const { return size_; }
    uint64_t budget_bytes() const { return budget_; }

    struct Stats {
        uint64_t resident_bytes = 0;       // regions counted as resident now
        uint64_t peak_resident_bytes = 0;  // largest resident_bytes so far
        uint64_t evictions = 0;
        uint64_t pins = 0;
    };
    Stats stats() const;
    // Whether region r is counted as resident (pinned or not yet evicted). For tests.
    bool resident(uint32_t r) const;

private:
    friend class RegionPin;
    void Unpin(uint32_t r);
    void TrimLocked();

    struct Region {
        uint64_t offset = 0, bytes = 0;
        uint32_t pins = 0;
        bool resident = false;
        uint64_t last_use = 0;
    };
    void DropPages(const Region& r);

    std::string path_;  // for messages; the file itself is unlinked
    int fd_ = -1;
    std::byte* data_ = nullptr;  // the read-only mapping, once Data() made it
    uint64_t size_ = 0;
    uint64_t budget_ = 0;
    std::vector<Region> regions_;
    mutable std::mutex mutex_;
    uint64_t clock_ = 0;
    Stats stats_;
};

}  // namespace mebake
