// The container of every binary file mebake writes (chart tiles, the visibility proxy,
// pyramids, checkpoints): a chunked format in the spirit of geogram's and RIFF.
//
//   header   magic "MEBK", kind (4 chars, e.g. "TILE"), version, chunk count,
//            table offset, table CRC, header CRC            (64 bytes)
//   chunks   each LZ4-compressed (or stored), 64-byte aligned
//   table    per chunk: tag (4 chars), index, codec, stored size, raw size, CRC-32 of
//            the stored bytes, offset
//
// Readers check the magic, kind, version and every CRC, name the file and the chunk on
// any mismatch, and skip chunks they do not know. Writers go through a temporary file,
// fsync and rename, so a crash never leaves a half-written file under the real name.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace mebake::io {

// Four characters packed little-endian: Tag("GRID").
constexpr uint32_t Tag(const char (&s)[5]) {
    return uint32_t(uint8_t(s[0])) | uint32_t(uint8_t(s[1])) << 8 |
           uint32_t(uint8_t(s[2])) << 16 | uint32_t(uint8_t(s[3])) << 24;
}
std::string TagName(uint32_t tag);

class ChunkWriter {
public:
    ChunkWriter(std::string path, uint32_t kind, uint32_t version);
    ~ChunkWriter();  // removes the temporary unless Finish() succeeded

    // Adds a chunk; `index` distinguishes repeated tags (e.g. one per chart).
    void Add(uint32_t tag, uint32_t index, std::span<const uint8_t> bytes, bool compress = true);
    template <typename T>
    void AddArray(uint32_t tag, uint32_t index, std::span<const T> v, bool compress = true) {
        static_assert(std::is_trivially_copyable_v<T>);
        Add(tag, index, {reinterpret_cast<const uint8_t*>(v.data()), v.size() * sizeof(T)},
            compress);
    }
    template <typename T>
    void AddArray(uint32_t tag, uint32_t index, const std::vector<T>& v, bool compress = true) {
        AddArray(tag, index, std::span<const T>(v), compress);
    }
    // Writes the table and header, fsyncs, renames into place. `durable` also fsyncs
    // the directory (checkpoints need it; bulk tiles can batch it).
    void Finish(bool durable = false);

    uint64_t bytes_written() const { return offset_; }

private:
    struct Entry;
    std::string path_, temp_;
    int fd_ = -1;
    uint32_t kind_, version_;
    uint64_t offset_ = 0;
    std::vector<Entry> entries_;
    std::vector<char> scratch_;
    bool finished_ = false;
    void WriteAt(const void* data, size_t n, uint64_t offset);
};

class ChunkReader {
    friend class ChunkWriter;

public:
    // Opens and validates the header and table. Throws Error(Corrupt) naming the file
    // when the magic, kind, version range or a CRC does not match, Error(Io) if missing.
    ChunkReader(std::string path, uint32_t kind, uint32_t min_version, uint32_t max_version);
    ~ChunkReader();
    ChunkReader(const ChunkReader&) = delete;
    ChunkReader& operator=(const ChunkReader&) = delete;

    uint32_t version() const { return version_; }
    const std::string& path() const { return path_; }
    bool Has(uint32_t tag, uint32_t index = 0) const;
    // Reads, checks and decompresses a chunk. Throws Error(Corrupt) naming file and chunk.
    // A chunk's CRC is checked at its first read through this reader only: the open file
    // does not change under it, and an export reads each chart's solution chunk once per
    // pass (the CRC was a tenth of a bake's outputs step, bench/RESULTS.md "Issue 13
    // (session 20)"). Thread-safe.
    std::vector<uint8_t> Read(uint32_t tag, uint32_t index = 0) const;
    template <typename T>
    std::vector<T> ReadArray(uint32_t tag, uint32_t index = 0) const {
        static_assert(std::is_trivially_copyable_v<T>);
        auto bytes = Read(tag, index);
        if (bytes.size() % sizeof(T) != 0) ThrowBadSize(tag, index, bytes.size(), sizeof(T));
        std::vector<T> out(bytes.size() / sizeof(T));
        if (!bytes.empty()) std::memcpy(out.data(), bytes.data(), bytes.size());
        return out;
    }
    // Every (tag, index) present, in file order.
    std::vector<std::pair<uint32_t, uint32_t>> List() const;

private:
    struct Entry;
    [[noreturn]] void ThrowBadSize(uint32_t tag, uint32_t index, size_t size, size_t elem) const;
    const Entry* Find(uint32_t tag, uint32_t index) const;
    std::string path_;
    int fd_ = -1;
    uint64_t file_size_ = 0;
    uint32_t version_ = 0;
    std::vector<Entry> entries_;
    std::unique_ptr<std::atomic<bool>[]> checked_;  // per entry: its CRC matched once
};

// Fsyncs a directory so renames inside it are durable.
void SyncDirectory(const std::string& dir);

}  // namespace mebake::io
