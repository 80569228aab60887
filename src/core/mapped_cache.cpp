#include "core/mapped_cache.h"

#include "core/check.h"
#include "core/error.h"
#include "core/temp_file.h"

#include <algorithm>
#include <cerrno>
#include <sys/mman.h>
#include <unistd.h>
#include <utility>

namespace mebake {

namespace {
// Regions start on page boundaries so that evicting one drops all of its pages.
constexpr uint64_t kAlign = 4096;
}  // namespace

RegionPin::RegionPin(RegionPin&& o) noexcept
    : cache_(std::exchange(o.cache_, nullptr)), region_(o.region_) {}

RegionPin& RegionPin::operator=(RegionPin&& o) noexcept {
    if (this != &o) {
        if (cache_)
            cache_->Unpin(region_);
        cache_ = std::exchange(o.cache_, nullptr);
        region_ = o.region_;
    }
    return *this;
}

RegionPin::~RegionPin() {
    if (cache_)
        cache_->Unpin(region_);
}

MappedCache::MappedCache(const std::string& dir, const std::string& what, uint64_t budget_bytes,
                         bool writable)
    : path_(dir + "/(" + what + ")"),
      fd_(OpenTemporaryFile(dir, what)),
      budget_(budget_bytes),
      writable_(writable) {}

MappedCache::~MappedCache() {
    if (data_)
        ::munmap(data_, size_);
    if (fd_ >= 0)
        ::close(fd_);
}

uint32_t MappedCache::Add(std::span<const std::span<const std::byte>> pieces) {
    std::lock_guard lock(mutex_);
    CHECK(data_ == nullptr);  // no Add() after Data()
    Region r;
    r.offset = (size_ + kAlign - 1) / kAlign * kAlign;
    uint64_t at = r.offset;
    for (const auto& piece : pieces) {
        const std::byte* p = piece.data();
        size_t left = piece.size();
        while (left > 0) {
            const ssize_t n = ::pwrite(fd_, p, left, off_t(at));
            if (n < 0 && errno == EINTR)
                continue;
            if (n <= 0)
                IoError({path_}, "cannot write {} bytes at {}: {}", left, at,
                        n < 0 ? ErrnoString(errno) : std::string("no progress"));
            p += n;
            at += uint64_t(n);
            left -= size_t(n);
        }
    }
    r.bytes = at - r.offset;
    size_ = at;
    regions_.push_back(r);
    return uint32_t(regions_.size() - 1);
}

std::byte* MappedCache::Map(uint32_t r) {
    CHECK_LT(r, regions_.size());
    std::lock_guard lock(mutex_);
    if (data_ == nullptr && size_ > 0) {
        const int prot = writable_ ? PROT_READ | PROT_WRITE : PROT_READ;
        void* p = ::mmap(nullptr, size_, prot, MAP_SHARED, fd_, 0);
        if (p == MAP_FAILED)
            IoError({path_}, "cannot map {} bytes: {}", size_, ErrnoString(errno));
        data_ = static_cast<std::byte*>(p);
    }
    return data_ + regions_[r].offset;
}

const std::byte* MappedCache::Data(uint32_t r) {
    return Map(r);
}

std::byte* MappedCache::MutableData(uint32_t r) {
    CHECK(writable_);
    return Map(r);
}

void MappedCache::DropPages(uint32_t victim) {
    if (data_ == nullptr)
        return;
    // Reading a page maps its neighbours too where they are in the page cache (the kernel's
    // fault-around, 64 KiB windows), pages of other regions that nothing counts, and that
    // their own eviction, done before, no longer drops. So 64 KiB on each side of the victim
    // go too, up to the pages of the nearest resident region.
    constexpr uint64_t kFaultAround = uint64_t(64) << 10;
    const uint64_t page = uint64_t(::sysconf(_SC_PAGESIZE));
    auto up = [](uint64_t x, uint64_t a) { return (x + a - 1) / a * a; };
    const Region& r = regions_[victim];
    // Any 64 KiB window that holds a page of the region (the kernel aligns them in the
    // address space, or starts them at the mapping's start).
    uint64_t begin = r.offset > kFaultAround ? r.offset - kFaultAround : 0;
    uint64_t end = std::min(up(r.offset + r.bytes, page) + kFaultAround, up(size_, page));
    for (uint32_t k = victim; k-- > 0 && regions_[k].offset + regions_[k].bytes > begin;)
        if (regions_[k].resident) {
            begin = std::max(begin, up(regions_[k].offset + regions_[k].bytes, page));
            break;
        }
    for (uint32_t k = victim + 1; k < regions_.size() && regions_[k].offset < end; ++k)
        if (regions_[k].resident) {
            end = std::min(end, regions_[k].offset);  // regions start on page boundaries
            break;
        }
    if (end > begin)
        ::madvise(data_ + begin, end - begin, MADV_DONTNEED);
}

RegionPin MappedCache::Pin(uint32_t r) {
    CHECK_LT(r, regions_.size());
    std::lock_guard lock(mutex_);
    Region& g = regions_[r];
    ++g.pins;
    ++stats_.pins;
    if (!g.resident) {
        g.resident = true;
        stats_.resident_bytes += g.bytes;
        stats_.peak_resident_bytes = std::max(stats_.peak_resident_bytes, stats_.resident_bytes);
    }
    return RegionPin(this, r);
}

void MappedCache::Unpin(uint32_t r) {
    std::lock_guard lock(mutex_);
    Region& g = regions_[r];
    CHECK_GT(g.pins, 0u);
    --g.pins;
    g.last_use = ++clock_;
    TrimLocked();
}

void MappedCache::TrimLocked() {
    while (stats_.resident_bytes > budget_) {
        Region* victim = nullptr;
        for (Region& g : regions_)
            if (g.resident && g.pins == 0 && (!victim || g.last_use < victim->last_use))
                victim = &g;
        if (!victim)
            return;  // everything resident is pinned
        DropPages(uint32_t(victim - regions_.data()));
        victim->resident = false;
        stats_.resident_bytes -= victim->bytes;
        ++stats_.evictions;
    }
}

MappedCache::Stats MappedCache::stats() const {
    std::lock_guard lock(mutex_);
    return stats_;
}

bool MappedCache::resident(uint32_t r) const {
    std::lock_guard lock(mutex_);
    return regions_[r].resident;
}

}  // namespace mebake
