// A large array on disk, read and written through a small fixed cache of pages: the cache
// for data looked up element by element (the ingest's vertex spill and binning, the
// positions behind `mebake info`, export's vertex colours). Its sibling for data read a
// region at a time (the solve's geometry pyramids) is core/mapped_cache.h.
//
// Why not mmap: touched pages of a file mapping count as this process's resident
// memory, so a 100M-vertex lookup table would make RSS grow with the mesh. Here the
// cache is the only memory held (pread/pwrite go through the kernel's page cache,
// which it can drop at will), and look-ups with locality — faces mostly name nearby
// vertices — hit the cache almost always.
#pragma once

#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

namespace mebake {

class PagedFile {
public:
    // Opens (creating if `create`) a file; `cache_bytes` of pages of `page_bytes` each.
    // `page_bytes` is a power of two.
    PagedFile(std::string path, bool create, size_t cache_bytes,
              size_t page_bytes = size_t(64) << 10);
    // An unlinked temporary file in `dir` (core/temp_file.h), made when the first page is
    // written back; `what` names it in messages.
    struct Temporary {
        std::string dir, what;
    };
    PagedFile(const Temporary& temp, size_t cache_bytes, size_t page_bytes = size_t(64) << 10);
    ~PagedFile();  // flushes dirty pages (errors are reported by Flush(), call it first)
    PagedFile(const PagedFile&) = delete;
    PagedFile& operator=(const PagedFile&) = delete;

    void Read(uint64_t offset, void* dst, size_t n);
    void Write(uint64_t offset, const void* src, size_t n);
    // Appends at the end of the logical size.
    void Append(const void* src, size_t n) { Write(size_, src, n); }
    void Flush();
    uint64_t size() const { return size_; }
    const std::string& path() const { return path_; }
    // Cache statistics, for benchmarks and tuning.
    uint64_t hits() const { return hits_; }
    uint64_t misses() const { return misses_; }

private:
    struct Page {
        uint64_t number = ~uint64_t(0);
        bool dirty = false;
        bool referenced = false;
    };
    void Init(size_t cache_bytes);
    uint8_t* Fetch(uint64_t page_number, bool for_write);
    uint8_t* Miss(uint64_t page_number, bool for_write);
    void WriteBack(size_t slot);

    std::string path_;
    std::optional<Temporary> temp_;  // a temporary file, opened by the first write-back
    int fd_ = -1;
    size_t page_bytes_;
    int page_shift_ = 0;
    uint64_t size_ = 0;       // logical size
    uint64_t disk_size_ = 0;  // bytes actually in the file
    std::vector<uint8_t> memory_;
    std::vector<Page> pages_;
    std::vector<int32_t> slot_of_;  // open-addressed map: page number hash -> slot
    size_t hand_ = 0;               // clock hand for eviction
    // The slots of recently used pages, by page number modulo kTlb: element look-ups hit
    // a few pages in turn, and this spares them the hash map.
    static constexpr size_t kTlb = 16;
    struct TlbEntry {
        uint64_t number = ~uint64_t(0);
        int32_t slot = -1;
    };
    TlbEntry tlb_[kTlb];
    uint64_t hits_ = 0, misses_ = 0;
    int32_t Lookup(uint64_t page_number) const;
    void MapInsert(uint64_t page_number, int32_t slot);
    void MapErase(uint64_t page_number);
};

// A typed view: element i lives at byte i * sizeof(T).
template <typename T>
class DiskArray {
    static_assert(std::is_trivially_copyable_v<T>);

public:
    DiskArray(std::string path, bool create, size_t cache_bytes)
        : file_(std::move(path), create, cache_bytes) {}
    DiskArray(const PagedFile::Temporary& temp, size_t cache_bytes) : file_(temp, cache_bytes) {}
    T Get(uint64_t i) {
        T v;
        file_.Read(i * sizeof(T), &v, sizeof(T));
        return v;
    }
    void Set(uint64_t i, const T& v) { file_.Write(i * sizeof(T), &v, sizeof(T)); }
    void Push(const T& v) { file_.Append(&v, sizeof(T)); }
    void PushMany(const T* v, size_t n) { file_.Append(v, n * sizeof(T)); }
    uint64_t size() const { return file_.size() / sizeof(T); }
    void Flush() { file_.Flush(); }
    PagedFile& file() { return file_; }

private:
    PagedFile file_;
};

}  // namespace mebake
