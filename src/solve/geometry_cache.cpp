#include "solve/geometry_cache.h"

#include "core/check.h"
#include "core/error.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <sys/mman.h>
#include <unistd.h>
#include <utility>

namespace mebake::solve {

namespace {

// Pyramids start on page boundaries so that evicting one drops all of its pages.
constexpr uint64_t kAlign = 4096;

uint64_t PyramidBytes(const stream::GeometryImage& image) {
    uint64_t n = 0;
    for (const auto& level : image.levels)
        n += level.size() * sizeof(stream::GeometryTexel);
    return n;
}

}  // namespace

GeometryPin::GeometryPin(GeometryPin&& o) noexcept
    : cache_(std::exchange(o.cache_, nullptr)), chart_(o.chart_) {}

GeometryPin& GeometryPin::operator=(GeometryPin&& o) noexcept {
    if (this != &o) {
        if (cache_)
            cache_->Unpin(chart_);
        cache_ = std::exchange(o.cache_, nullptr);
        chart_ = o.chart_;
    }
    return *this;
}

GeometryPin::~GeometryPin() {
    if (cache_)
        cache_->Unpin(chart_);
}

GeometryPyramid::GeometryPyramid(stream::GeometryImage image)
    : owned_(std::make_shared<const stream::GeometryImage>(std::move(image))) {
    resolution = owned_->resolution;
    for (const auto& level : owned_->levels)
        levels.emplace_back(level);
}

GeometryPin GeometryPyramid::Pin() const {
    return cache_ ? cache_->Pin(chart_) : GeometryPin();
}

stream::SurfaceSample SampleBilinear(const GeometryPyramid& img, int level, float u, float v) {
    return stream::SampleBilinearOf(img, level, u, v);
}

GeometryCache::GeometryCache(const std::string& dir, uint64_t budget_bytes)
    : budget_(budget_bytes) {
    path_ =
        (std::filesystem::path(dir) / ("geometry." + std::to_string(::getpid()) + ".tmp")).string();
    fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd_ < 0)
        IoError({path_}, "cannot create: {}", ErrnoString(errno));
    ::unlink(path_.c_str());  // the descriptor keeps the file alive
}

GeometryCache::~GeometryCache() {
    if (data_)
        ::munmap(data_, size_);
    if (fd_ >= 0)
        ::close(fd_);
}

uint32_t GeometryCache::Add(const stream::GeometryImage& image) {
    CHECK(!image.levels.empty());
    CHECK(data_ == nullptr);  // no Add() after View()
    Entry e;
    e.offset = (size_ + kAlign - 1) / kAlign * kAlign;
    e.bytes = PyramidBytes(image);
    e.resolution = image.resolution;
    uint64_t at = e.offset;
    for (const auto& level : image.levels) {
        e.level_sizes.push_back(level.size());
        const auto* p = reinterpret_cast<const uint8_t*>(level.data());
        size_t left = level.size() * sizeof(stream::GeometryTexel);
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
    size_ = at;
    entries_.push_back(e);
    return uint32_t(entries_.size() - 1);
}

GeometryPyramid GeometryCache::View(uint32_t c) {
    CHECK_LT(c, entries_.size());
    if (data_ == nullptr && size_ > 0) {
        void* p = ::mmap(nullptr, size_, PROT_READ, MAP_SHARED, fd_, 0);
        if (p == MAP_FAILED)
            IoError({path_}, "cannot map {} bytes: {}", size_, ErrnoString(errno));
        data_ = static_cast<uint8_t*>(p);
    }
    const Entry& e = entries_[c];
    GeometryPyramid p;
    p.resolution = e.resolution;
    p.cache_ = this;
    p.chart_ = c;
    const auto* texels = reinterpret_cast<const stream::GeometryTexel*>(data_ + e.offset);
    for (size_t n : e.level_sizes) {
        p.levels.emplace_back(texels, n);
        texels += n;
    }
    return p;
}

void GeometryCache::DropPages(const Entry& e) {
    if (data_ == nullptr)
        return;
    // Whole pages only: pyramids start on page boundaries, and the last one ends the file.
    const uint64_t page = uint64_t(::sysconf(_SC_PAGESIZE));
    const uint64_t begin = (e.offset + page - 1) / page * page;
    const uint64_t end =
        std::min((e.offset + e.bytes + page - 1) / page * page, (size_ + page - 1) / page * page);
    if (end > begin)
        ::madvise(data_ + begin, end - begin, MADV_DONTNEED);
}

GeometryPin GeometryCache::Pin(uint32_t c) {
    std::lock_guard lock(mutex_);
    Entry& e = entries_[c];
    ++e.pins;
    ++stats_.pins;
    if (!e.resident) {
        e.resident = true;
        stats_.resident_bytes += e.bytes;
        stats_.peak_resident_bytes = std::max(stats_.peak_resident_bytes, stats_.resident_bytes);
    }
    return GeometryPin(this, c);
}

void GeometryCache::Unpin(uint32_t c) {
    std::lock_guard lock(mutex_);
    Entry& e = entries_[c];
    CHECK_GT(e.pins, 0u);
    --e.pins;
    e.last_use = ++clock_;
    TrimLocked();
}

void GeometryCache::TrimLocked() {
    while (stats_.resident_bytes > budget_) {
        Entry* victim = nullptr;
        for (Entry& e : entries_)
            if (e.resident && e.pins == 0 && (!victim || e.last_use < victim->last_use))
                victim = &e;
        if (!victim)
            return;  // everything resident is pinned
        DropPages(*victim);
        victim->resident = false;
        stats_.resident_bytes -= victim->bytes;
        ++stats_.evictions;
    }
}

GeometryCache::Stats GeometryCache::stats() const {
    std::lock_guard lock(mutex_);
    return stats_;
}

bool GeometryCache::resident(uint32_t c) const {
    std::lock_guard lock(mutex_);
    return entries_[c].resident;
}

}  // namespace mebake::solve
