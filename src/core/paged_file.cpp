#include "core/paged_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "core/check.h"
#include "core/error.h"
#include "core/temp_file.h"

namespace mebake {

namespace {
uint64_t HashPage(uint64_t x) {
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdull;
    x ^= x >> 33;
    return x;
}
}  // namespace

PagedFile::PagedFile(std::string path, bool create, size_t cache_bytes, size_t page_bytes)
    : path_(std::move(path)), page_bytes_(page_bytes) {
    fd_ = ::open(path_.c_str(), create ? (O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC) : (O_RDWR | O_CLOEXEC),
                 0644);
    if (fd_ < 0 && !create && errno == EACCES) fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) IoError({path_}, "cannot open: {}", ErrnoString(errno));
    struct stat st {};
    ::fstat(fd_, &st);
    size_ = disk_size_ = uint64_t(st.st_size);
    Init(cache_bytes);
}

PagedFile::PagedFile(const Temporary& temp, size_t cache_bytes, size_t page_bytes)
    : path_(TemporaryDirectory(temp.dir) + "/(" + temp.what + ")"), temp_(temp), page_bytes_(page_bytes) {
    Init(cache_bytes);  // the file is made by the first write-back: small data never touches disk
}

void PagedFile::Init(size_t cache_bytes) {
    CHECK(page_bytes_ > 0 && (page_bytes_ & (page_bytes_ - 1)) == 0);
    while ((size_t(1) << page_shift_) < page_bytes_) ++page_shift_;
    size_t count = std::max<size_t>(4, cache_bytes / page_bytes_);
    memory_.resize(count * page_bytes_);
    pages_.resize(count);
    size_t map_size = 1;
    while (map_size < count * 2) map_size <<= 1;
    slot_of_.assign(map_size, -1);
}

PagedFile::~PagedFile() {
    try {
        Flush();
    } catch (...) {
        // Reported by an explicit Flush(); a destructor must not throw.
    }
    if (fd_ >= 0) ::close(fd_);
}

int32_t PagedFile::Lookup(uint64_t page_number) const {
    size_t mask = slot_of_.size() - 1;
    for (size_t h = HashPage(page_number) & mask;; h = (h + 1) & mask) {
        int32_t s = slot_of_[h];
        if (s < 0) return -1;
        if (pages_[size_t(s)].number == page_number) return s;
    }
}

void PagedFile::MapInsert(uint64_t page_number, int32_t slot) {
    size_t mask = slot_of_.size() - 1;
    size_t h = HashPage(page_number) & mask;
    while (slot_of_[h] >= 0) h = (h + 1) & mask;
    slot_of_[h] = slot;
}

void PagedFile::MapErase(uint64_t page_number) {
    // Linear probing deletion: remove and re-insert the rest of the cluster.
    size_t mask = slot_of_.size() - 1;
    size_t h = HashPage(page_number) & mask;
    while (slot_of_[h] >= 0 && pages_[size_t(slot_of_[h])].number != page_number) h = (h + 1) & mask;
    if (slot_of_[h] < 0) return;
    slot_of_[h] = -1;
    for (size_t k = (h + 1) & mask; slot_of_[k] >= 0; k = (k + 1) & mask) {
        int32_t s = slot_of_[k];
        slot_of_[k] = -1;
        MapInsert(pages_[size_t(s)].number, s);
    }
}

void PagedFile::WriteBack(size_t slot) {
    Page& p = pages_[slot];
    if (!p.dirty) return;
    if (fd_ < 0) fd_ = OpenTemporaryFile(temp_->dir, temp_->what);
    uint64_t off = p.number * page_bytes_;
    size_t n = size_t(std::min<uint64_t>(page_bytes_, size_ > off ? size_ - off : 0));
    const uint8_t* src = memory_.data() + slot * page_bytes_;
    size_t done = 0;
    while (done < n) {
        ssize_t w = ::pwrite(fd_, src + done, n - done, off_t(off + done));
        if (w < 0) {
            if (errno == EINTR) continue;
            IoError({path_}, "write failed: {}", ErrnoString(errno));
        }
        done += size_t(w);
    }
    disk_size_ = std::max<uint64_t>(disk_size_, off + n);
    p.dirty = false;
}

uint8_t* PagedFile::Fetch(uint64_t page_number, bool for_write) {
    TlbEntry& t = tlb_[page_number % kTlb];
    int32_t s = t.number == page_number ? t.slot : Lookup(page_number);
    if (s < 0) return Miss(page_number, for_write);
    ++hits_;
    t = {page_number, s};
    Page& p = pages_[size_t(s)];
    p.referenced = true;
    if (for_write) p.dirty = true;
    return memory_.data() + (size_t(s) << page_shift_);
}

uint8_t* PagedFile::Miss(uint64_t page_number, bool for_write) {
    ++misses_;
    // Clock eviction: skip recently referenced pages once.
    size_t slot;
    for (;;) {
        slot = hand_;
        hand_ = (hand_ + 1) % pages_.size();
        if (!pages_[slot].referenced) break;
        pages_[slot].referenced = false;
    }
    Page& p = pages_[slot];
    if (p.number != ~uint64_t(0)) {
        WriteBack(slot);
        MapErase(p.number);
        TlbEntry& old = tlb_[p.number % kTlb];
        if (old.number == p.number) old = TlbEntry{};
    }
    uint8_t* dst = memory_.data() + (slot << page_shift_);
    uint64_t off = page_number << page_shift_;
    size_t have = size_t(std::min<uint64_t>(page_bytes_, disk_size_ > off ? disk_size_ - off : 0));
    size_t done = 0;
    while (done < have) {
        ssize_t r = ::pread(fd_, dst + done, have - done, off_t(off + done));
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) IoError({path_, off + done}, "read failed: {}", r < 0 ? ErrnoString(errno) : "unexpected end");
        done += size_t(r);
    }
    std::memset(dst + have, 0, page_bytes_ - have);
    p.number = page_number;
    p.dirty = for_write;
    p.referenced = true;
    MapInsert(page_number, int32_t(slot));
    tlb_[page_number % kTlb] = {page_number, int32_t(slot)};
    return dst;
}

void PagedFile::Read(uint64_t offset, void* dst, size_t n) {
    CHECK_LE(offset + n, size_);
    auto out = static_cast<uint8_t*>(dst);
    while (n > 0) {
        uint64_t pn = offset >> page_shift_;
        size_t in_page = size_t(offset & (page_bytes_ - 1));
        size_t k = std::min(n, page_bytes_ - in_page);
        std::memcpy(out, Fetch(pn, false) + in_page, k);
        out += k;
        offset += k;
        n -= k;
    }
}

void PagedFile::Write(uint64_t offset, const void* src, size_t n) {
    auto in = static_cast<const uint8_t*>(src);
    if (offset + n > size_) size_ = offset + n;
    while (n > 0) {
        uint64_t pn = offset >> page_shift_;
        size_t in_page = size_t(offset & (page_bytes_ - 1));
        size_t k = std::min(n, page_bytes_ - in_page);
        std::memcpy(Fetch(pn, true) + in_page, in, k);
        in += k;
        offset += k;
        n -= k;
    }
}

void PagedFile::Flush() {
    for (size_t s = 0; s < pages_.size(); ++s)
        if (pages_[s].number != ~uint64_t(0)) WriteBack(s);
}

}  // namespace mebake
