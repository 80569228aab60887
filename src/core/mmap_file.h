// A file mapped into memory: read-only views of existing files, and growable
// read-write files for spills and pyramids. Pages are backed by the file, so the kernel
// can drop them under pressure: resident memory follows what is touched, not file size.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace mebake {

class MappedFile {
public:
    enum class Mode { ReadOnly, ReadWrite };

    MappedFile() = default;
    ~MappedFile();
    MappedFile(MappedFile&& o) noexcept;
    MappedFile& operator=(MappedFile&& o) noexcept;
    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;

    // Maps an existing file. Throws Error(Io) naming the path.
    static MappedFile Open(const std::string& path, Mode mode = Mode::ReadOnly);
    // Creates (truncates) a file of `size` bytes, mapped read-write.
    static MappedFile Create(const std::string& path, uint64_t size);

    // Grows or shrinks a read-write mapping; the data pointer may move.
    void Resize(uint64_t size);
    // Flushes dirty pages to disk (msync) and, if `durable`, fsyncs the file.
    void Sync(bool durable = false);
    // Tells the kernel the pages in [offset, offset+len) will not be needed soon.
    void DontNeed(uint64_t offset, uint64_t len);
    void Close();

    bool is_open() const { return fd_ >= 0; }
    uint64_t size() const { return size_; }
    const std::string& path() const { return path_; }
    uint8_t* data() { return static_cast<uint8_t*>(data_); }
    const uint8_t* data() const { return static_cast<const uint8_t*>(data_); }
    std::span<const uint8_t> bytes() const { return {data(), size_}; }

private:
    std::string path_;
    int fd_ = -1;
    void* data_ = nullptr;
    uint64_t size_ = 0;
    uint64_t mapped_ = 0;  // bytes mapped (>= size_, page-rounded capacity)
    Mode mode_ = Mode::ReadOnly;
};

}  // namespace mebake
