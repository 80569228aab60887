#include "io/chunk_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cerrno>
#include <filesystem>
#include <limits>

#include "core/checksum.h"
#include "core/error.h"
#include "io/lz4_block.h"

namespace mebake::io {

namespace {
constexpr uint32_t kMagic = 0x4B42454D;  // "MEBK"
constexpr uint64_t kAlign = 64;
constexpr uint32_t kCodecStored = 0, kCodecLz4 = 1;

struct Header {
    uint32_t magic, kind, version, chunk_count;
    uint64_t table_offset;
    uint32_t table_crc, reserved0;
    uint8_t reserved[28];
    uint32_t header_crc;  // CRC of the 60 bytes before it
};
static_assert(sizeof(Header) == 64);

uint64_t AlignUp(uint64_t x) { return (x + kAlign - 1) / kAlign * kAlign; }
}  // namespace

struct ChunkWriter::Entry {
    uint32_t tag, index, codec, crc;
    uint64_t offset, stored_size, raw_size;
};
struct ChunkReader::Entry {
    uint32_t tag, index, codec, crc;
    uint64_t offset, stored_size, raw_size;
};

std::string TagName(uint32_t tag) {
    std::string s(4, '?');
    for (int i = 0; i < 4; ++i) {
        char c = char((tag >> (8 * i)) & 0xFF);
        s[size_t(i)] = (c >= 32 && c < 127) ? c : '?';
    }
    return s;
}

ChunkWriter::ChunkWriter(std::string path, uint32_t kind, uint32_t version)
    : path_(std::move(path)), kind_(kind), version_(version) {
    std::filesystem::path p(path_);
    std::string dir = p.has_parent_path() ? p.parent_path().string() : ".";
    std::string tmpl = dir + "/." + p.filename().string() + ".tmp-XXXXXX";
    std::vector<char> buf(tmpl.begin(), tmpl.end());
    buf.push_back('\0');
    fd_ = ::mkostemp(buf.data(), O_CLOEXEC);
    if (fd_ < 0) IoError({path_}, "cannot create: {}", ErrnoString(errno));
    temp_ = buf.data();
    ::fchmod(fd_, 0644);
    offset_ = sizeof(Header);
}

ChunkWriter::~ChunkWriter() {
    if (fd_ >= 0) ::close(fd_);
    if (!finished_ && !temp_.empty()) ::unlink(temp_.c_str());
}

// Test hook: MEBAKE_FAIL_WRITE_AFTER=<bytes> makes every chunk file write fail once this
// process has written that many bytes through ChunkWriter, as a full disk would.
static uint64_t InjectedWriteLimit() {
    static const uint64_t limit = [] {
        const char* s = std::getenv("MEBAKE_FAIL_WRITE_AFTER");
        return s ? std::strtoull(s, nullptr, 10) : std::numeric_limits<uint64_t>::max();
    }();
    return limit;
}

void ChunkWriter::WriteAt(const void* data, size_t n, uint64_t offset) {
    static std::atomic<uint64_t> total{0};
    if ((total += n) > InjectedWriteLimit())
        IoError({path_}, "write failed: {} (injected by MEBAKE_FAIL_WRITE_AFTER)",
                ErrnoString(ENOSPC));
    auto p = static_cast<const char*>(data);
    while (n > 0) {
        ssize_t w = ::pwrite(fd_, p, n, off_t(offset));
        if (w < 0) {
            if (errno == EINTR) continue;
            IoError({path_}, "write failed: {}", ErrnoString(errno));
        }
        p += w;
        n -= size_t(w);
        offset += uint64_t(w);
    }
}

void ChunkWriter::Add(uint32_t tag, uint32_t index, std::span<const uint8_t> bytes,
                      bool compress) {
    Entry e{tag, index, kCodecStored, 0, AlignUp(offset_), 0, bytes.size()};
    std::span<const uint8_t> stored = bytes;
    if (compress && bytes.size() > 64) {
        scratch_.clear();
        AppendLz4(bytes, &scratch_);
        if (scratch_.size() < bytes.size()) {
            e.codec = kCodecLz4;
            stored = {reinterpret_cast<const uint8_t*>(scratch_.data()), scratch_.size()};
        }
    }
    e.stored_size = stored.size();
    e.crc = Crc32(stored.data(), stored.size());
    if (!stored.empty()) WriteAt(stored.data(), stored.size(), e.offset);
    offset_ = e.offset + e.stored_size;
    entries_.push_back(e);
}

void ChunkWriter::Finish(bool durable) {
    static_assert(sizeof(Entry) == 40 && sizeof(Entry) == sizeof(ChunkReader::Entry));
    Header h{};
    h.magic = kMagic;
    h.kind = kind_;
    h.version = version_;
    h.chunk_count = uint32_t(entries_.size());
    h.table_offset = AlignUp(offset_);
    h.table_crc = Crc32(entries_.data(), entries_.size() * sizeof(Entry));
    h.header_crc = Crc32(&h, offsetof(Header, header_crc));
    if (!entries_.empty()) WriteAt(entries_.data(), entries_.size() * sizeof(Entry), h.table_offset);
    WriteAt(&h, sizeof(h), 0);
    if (::fsync(fd_) != 0) IoError({path_}, "fsync failed: {}", ErrnoString(errno));
    ::close(fd_);
    fd_ = -1;
    if (::rename(temp_.c_str(), path_.c_str()) != 0)
        IoError({path_}, "cannot rename into place: {}", ErrnoString(errno));
    finished_ = true;
    if (durable) {
        std::filesystem::path p(path_);
        SyncDirectory(p.has_parent_path() ? p.parent_path().string() : ".");
    }
}

ChunkReader::ChunkReader(std::string path, uint32_t kind, uint32_t min_version,
                         uint32_t max_version)
    : path_(std::move(path)) {
    fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) IoError({path_}, "cannot open: {}", ErrnoString(errno));
    struct stat st {};
    ::fstat(fd_, &st);
    file_size_ = uint64_t(st.st_size);
    Header h{};
    if (file_size_ < sizeof(Header) || ::pread(fd_, &h, sizeof(h), 0) != ssize_t(sizeof(h)))
        CorruptError({path_, 0}, "truncated: shorter than its 64-byte header");
    if (h.magic != kMagic) CorruptError({path_, 0}, "not a mebake file (bad magic)");
    if (h.header_crc != Crc32(&h, offsetof(Header, header_crc)))
        CorruptError({path_, 0}, "header checksum mismatch");
    if (h.kind != kind)
        CorruptError({path_, 4}, "is a {} file, expected {}", TagName(h.kind), TagName(kind));
    if (h.version < min_version || h.version > max_version)
        CorruptError({path_, 8}, "format version {} is not supported (expected {}..{})",
                     h.version, min_version, max_version);
    version_ = h.version;
    uint64_t table_bytes = uint64_t(h.chunk_count) * sizeof(Entry);
    if (h.table_offset > file_size_ || table_bytes > file_size_ - h.table_offset)
        CorruptError({path_, h.table_offset}, "truncated: chunk table past the end of the file");
    entries_.resize(h.chunk_count);
    if (table_bytes &&
        ::pread(fd_, entries_.data(), table_bytes, off_t(h.table_offset)) != ssize_t(table_bytes))
        CorruptError({path_, h.table_offset}, "cannot read the chunk table");
    if (Crc32(entries_.data(), table_bytes) != h.table_crc)
        CorruptError({path_, h.table_offset}, "chunk table checksum mismatch");
    for (const auto& e : entries_)
        if (e.offset > file_size_ || e.stored_size > file_size_ - e.offset)
            CorruptError({path_, e.offset}, "chunk {}[{}] runs past the end of the file",
                         TagName(e.tag), e.index);
    checked_ = std::make_unique<std::atomic<bool>[]>(entries_.size());
}

ChunkReader::~ChunkReader() {
    if (fd_ >= 0) ::close(fd_);
}

const ChunkReader::Entry* ChunkReader::Find(uint32_t tag, uint32_t index) const {
    for (const auto& e : entries_)
        if (e.tag == tag && e.index == index) return &e;
    return nullptr;
}

bool ChunkReader::Has(uint32_t tag, uint32_t index) const { return Find(tag, index) != nullptr; }

std::vector<std::pair<uint32_t, uint32_t>> ChunkReader::List() const {
    std::vector<std::pair<uint32_t, uint32_t>> out;
    for (const auto& e : entries_) out.emplace_back(e.tag, e.index);
    return out;
}

void ChunkReader::ThrowBadSize(uint32_t tag, uint32_t index, size_t size, size_t elem) const {
    CorruptError({path_}, "chunk {}[{}] has {} bytes, not a multiple of {}", TagName(tag), index,
                 size, elem);
}

std::vector<uint8_t> ChunkReader::Read(uint32_t tag, uint32_t index) const {
    const Entry* e = Find(tag, index);
    if (!e) CorruptError({path_}, "chunk {}[{}] is missing", TagName(tag), index);
    std::vector<uint8_t> stored(e->stored_size);
    uint64_t done = 0;
    while (done < e->stored_size) {
        ssize_t n = ::pread(fd_, stored.data() + done, e->stored_size - done,
                            off_t(e->offset + done));
        if (n <= 0) {
            if (n < 0 && errno == EINTR) continue;
            CorruptError({path_, e->offset + done}, "cannot read chunk {}[{}]", TagName(tag), index);
        }
        done += uint64_t(n);
    }
    std::atomic<bool>& checked = checked_[size_t(e - entries_.data())];
    if (!checked.load(std::memory_order_relaxed)) {
        if (Crc32(stored.data(), stored.size()) != e->crc)
            CorruptError({path_, e->offset}, "chunk {}[{}] checksum mismatch (damaged file)",
                         TagName(tag), index);
        checked.store(true, std::memory_order_relaxed);
    }
    if (e->codec == kCodecStored) {
        if (e->raw_size != e->stored_size)
            CorruptError({path_, e->offset}, "chunk {}[{}] size mismatch", TagName(tag), index);
        return stored;
    }
    if (e->codec != kCodecLz4)
        CorruptError({path_, e->offset}, "chunk {}[{}] has unknown codec {}", TagName(tag), index,
                     e->codec);
    if (e->raw_size > (uint64_t(1) << 40))
        CorruptError({path_, e->offset}, "chunk {}[{}] claims an absurd size", TagName(tag), index);
    std::vector<uint8_t> raw(e->raw_size);
    if (!DecodeLz4(stored, raw))
        CorruptError({path_, e->offset}, "chunk {}[{}] does not decompress", TagName(tag), index);
    return raw;
}

void SyncDirectory(const std::string& dir) {
    int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) IoError({dir}, "cannot open directory: {}", ErrnoString(errno));
    int rc = ::fsync(fd);
    int err = errno;
    ::close(fd);
    if (rc != 0) IoError({dir}, "cannot sync directory: {}", ErrnoString(err));
}

}  // namespace mebake::io
