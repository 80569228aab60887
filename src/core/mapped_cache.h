// Regions of one unlinked file, memory-mapped, with RAII pins and a residency budget: the
// cache for data that is worked on a region at a time (the solve's geometry pyramids and
// coefficient pools, one region per chart). Its sibling for data looked up element by
// element is core/paged_file.h.
//
// Regions are appended once (each starts on a page boundary), then the file is mapped:
// read-only by default, so its pages are clean page-cache pages and dropping them costs
// no write; or writable (the coefficient pools), where a dropped dirty page stays in the
// page cache and the kernel writes it back to the file. Appending writes every byte of a
// region, so the file's blocks exist before the mapping and a store through it never has
// to allocate disk (a full disk is an Error from Add(), never a SIGBUS later). A pass
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
    // ones. writable: the mapping may be written through MutableData(). Throws Error(Io).
    MappedCache(const std::string& dir, const std::string& what, uint64_t budget_bytes,
                bool writable = false);
    ~MappedCache();
    MappedCache(const MappedCache&) = delete;
    MappedCache& operator=(const MappedCache&) = delete;

    // Appends a region made of `pieces`, in order (regions are numbered in the order
    // added; calls from several threads are serialized). Every Add() comes before the
    // first Data(). Throws Error(Io) (a full disk): callers can keep their data in memory
    // instead.
    uint32_t Add(std::span<const std::span<const std::byte>> pieces);
    // The bytes of region r (the first call maps the file); valid while the cache lives.
    // Read them while holding a pin.
    const std::byte* Data(uint32_t r);
    // The same bytes, writable (a writable cache only); write them while holding a pin.
    std::byte* MutableData(uint32_t r);
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
    bool writable() const { return writable_; }

private:
    friend class RegionPin;
    void Unpin(uint32_t r);
    void TrimLocked();
    std::byte* Map(uint32_t r);  // maps the file on the first call

    struct Region {
        uint64_t offset = 0, bytes = 0;
        uint32_t pins = 0;
        bool resident = false;
        uint64_t last_use = 0;
    };
    void DropPages(uint32_t victim);  // its pages and the unaccounted ones around it

    std::string path_;  // for messages; the file itself is unlinked
    int fd_ = -1;
    uint64_t budget_ = 0;
    bool writable_ = false;
    std::byte* data_ = nullptr;  // the mapping, once Data() made it
    uint64_t size_ = 0;
    std::vector<Region> regions_;
    mutable std::mutex mutex_;
    uint64_t clock_ = 0;
    Stats stats_;
};

}  // namespace mebake
