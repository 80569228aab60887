// Buffered byte streams over a file or a pipe ("-" is stdin/stdout).
// Input tracks the byte offset consumed so far, so parsers can name the position of an
// error. Output to a named file goes to a temporary beside it and is renamed into place
// only by Commit(), so a failed or interrupted write never destroys what the user had.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace mebake::io {

class InputStream {
public:
    // Opens `path`, or stdin when path is "-". Throws Error(Io) naming the path.
    static std::unique_ptr<InputStream> Open(const std::string& path);
    // Wraps an in-memory buffer (tests, fuzzers). The bytes must outlive the stream.
    static std::unique_ptr<InputStream> FromMemory(std::span<const uint8_t> bytes,
                                                   std::string name = "<memory>");
    ~InputStream();

    const std::string& name() const { return name_; }  // path, or "<stdin>"
    uint64_t offset() const { return consumed_; }        // bytes consumed so far
    uint64_t size_hint() const { return size_hint_; }    // file size if known, else 0

    // Makes at least n bytes available (fewer only at end of stream) and returns all
    // buffered bytes; n may be up to kMaxPeek.
    std::span<const uint8_t> Peek(size_t n);
    // Consumes n bytes that were returned by Peek.
    void Skip(size_t n);
    // Reads up to n bytes into dst; returns how many (0 at end of stream).
    size_t Read(void* dst, size_t n);
    // Reads one line without its terminator ("\n" or "\r\n"). Returns false at end of
    // stream. Lines longer than kMaxLine are an input error naming the offset.
    bool ReadLine(std::string& line);
    bool AtEnd();

    static constexpr size_t kBufferSize = size_t(1) << 20;
    static constexpr size_t kMaxPeek = kBufferSize / 2;
    static constexpr size_t kMaxLine = size_t(1) << 20;

private:
    InputStream() = default;
    void Fill(size_t want);

    std::string name_;
    int fd_ = -1;
    bool owns_fd_ = false;
    bool eof_ = false;
    std::vector<uint8_t> buffer_;
    std::span<const uint8_t> memory_;  // used instead of fd_ when non-empty or memory mode
    bool memory_mode_ = false;
    size_t begin_ = 0, end_ = 0;  // valid bytes are buffer_[begin_, end_)
    uint64_t consumed_ = 0;
    uint64_t size_hint_ = 0;
};

// Every byte of `path` (or stdin for "-"). Throws Error(Io) naming the path.
std::vector<uint8_t> ReadWholeFile(const std::string& path);

class OutputStream {
public:
    // "-" writes to stdout; otherwise to a temporary file beside `path` that Commit()
    // renames over `path`. Throws Error(Io) naming the path.
    static std::unique_ptr<OutputStream> Open(const std::string& path);
    // Collects everything in memory (tests).
    static std::unique_ptr<OutputStream> ToMemory(std::vector<uint8_t>* sink);
    // Without Commit() the temporary is removed and `path` is left untouched.
    ~OutputStream();

    const std::string& name() const { return name_; }
    uint64_t offset() const { return written_; }
    bool is_stdout() const { return fd_ == 1; }

    void Write(const void* data, size_t n);
    void Write(std::string_view s) { Write(s.data(), s.size()); }
    void Flush();
    // Flushes, fsyncs and renames the temporary into place (no-op rename for stdout).
    void Commit();

private:
    OutputStream() = default;

    std::string name_, temp_;
    int fd_ = -1;
    std::vector<uint8_t>* memory_ = nullptr;
    std::vector<uint8_t> buffer_;
    uint64_t written_ = 0;
    bool committed_ = false;
};

}  // namespace mebake::io
