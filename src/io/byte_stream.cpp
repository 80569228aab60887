#include "io/byte_stream.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/error.h"

namespace mebake::io {

std::unique_ptr<InputStream> InputStream::Open(const std::string& path) {
    std::unique_ptr<InputStream> s(new InputStream());
    if (path == "-") {
        s->name_ = "<stdin>";
        s->fd_ = 0;
    } else {
        s->name_ = path;
        s->fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        if (s->fd_ < 0) IoError({path}, "cannot open: {}", ErrnoString(errno));
        s->owns_fd_ = true;
        struct stat st {};
        if (::fstat(s->fd_, &st) == 0) {
            if (S_ISDIR(st.st_mode)) IoError({path}, "is a directory, expected a mesh file");
            if (S_ISREG(st.st_mode)) s->size_hint_ = uint64_t(st.st_size);
        }
        ::posix_fadvise(s->fd_, 0, 0, POSIX_FADV_SEQUENTIAL);
    }
    s->buffer_.resize(kBufferSize);
    return s;
}

std::unique_ptr<InputStream> InputStream::FromMemory(std::span<const uint8_t> bytes,
                                                     std::string name) {
    std::unique_ptr<InputStream> s(new InputStream());
    s->name_ = std::move(name);
    s->memory_mode_ = true;
    s->memory_ = bytes;
    s->size_hint_ = bytes.size();
    s->eof_ = true;
    return s;
}

InputStream::~InputStream() {
    if (owns_fd_ && fd_ >= 0) ::close(fd_);
}

void InputStream::Fill(size_t want) {
    if (memory_mode_) return;
    if (end_ - begin_ >= want || eof_) return;
    // Move the unread tail to the front, then read until `want` bytes or EOF.
    if (begin_ > 0) {
        std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
        end_ -= begin_;
        begin_ = 0;
    }
    while (end_ < want && !eof_) {
        ssize_t n = ::read(fd_, buffer_.data() + end_, buffer_.size() - end_);
        if (n < 0) {
            if (errno == EINTR) continue;
            IoError({name_, consumed_ + (end_ - begin_)}, "read failed: {}", ErrnoString(errno));
        }
        if (n == 0) eof_ = true;
        end_ += size_t(n);
    }
}

std::span<const uint8_t> InputStream::Peek(size_t n) {
    if (memory_mode_) {
        size_t pos = size_t(consumed_);
        return memory_.subspan(pos);
    }
    Fill(std::min(n, kMaxPeek));
    return {buffer_.data() + begin_, end_ - begin_};
}

void InputStream::Skip(size_t n) {
    if (memory_mode_) {
        consumed_ += std::min<uint64_t>(n, memory_.size() - consumed_);
        return;
    }
    n = std::min(n, end_ - begin_);
    begin_ += n;
    consumed_ += n;
}

size_t InputStream::Read(void* dst, size_t n) {
    auto out = static_cast<uint8_t*>(dst);
    size_t done = 0;
    while (done < n) {
        auto avail = Peek(std::min(n - done, kMaxPeek));
        if (avail.empty()) break;
        size_t k = std::min(avail.size(), n - done);
        std::memcpy(out + done, avail.data(), k);
        Skip(k);
        done += k;
    }
    return done;
}

bool InputStream::AtEnd() { return Peek(1).empty(); }

bool InputStream::ReadLine(std::string& line) {
    line.clear();
    for (;;) {
        auto avail = Peek(4096);
        if (avail.empty()) return !line.empty();
        auto nl = std::find(avail.begin(), avail.end(), uint8_t('\n'));
        size_t k = size_t(nl - avail.begin());
        line.append(reinterpret_cast<const char*>(avail.data()), k);
        if (line.size() > kMaxLine)
            InputError({name_, consumed_}, "line longer than {} bytes (binary data?)", kMaxLine);
        if (nl != avail.end()) {
            Skip(k + 1);
            if (!line.empty() && line.back() == '\r') line.pop_back();
            return true;
        }
        Skip(k);
    }
}

std::unique_ptr<OutputStream> OutputStream::Open(const std::string& path) {
    std::unique_ptr<OutputStream> s(new OutputStream());
    if (path == "-") {
        s->name_ = "<stdout>";
        s->fd_ = 1;
    } else if (struct stat st {}; ::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
        // A device, FIFO or socket (/dev/null, a named pipe): write to it directly. The
        // temporary-and-rename path would replace the device with a regular file.
        if (S_ISDIR(st.st_mode)) IoError({path}, "is a directory, expected an output file");
        s->name_ = path;
        s->fd_ = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
        if (s->fd_ < 0) IoError({path}, "cannot open for writing: {}", ErrnoString(errno));
    } else {
        s->name_ = path;
        std::filesystem::path p(path);
        std::string dir = p.has_parent_path() ? p.parent_path().string() : ".";
        std::string tmpl = dir + "/." + p.filename().string() + ".tmp-XXXXXX";
        std::vector<char> buf(tmpl.begin(), tmpl.end());
        buf.push_back('\0');
        s->fd_ = ::mkostemp(buf.data(), O_CLOEXEC);
        if (s->fd_ < 0) IoError({path}, "cannot create output: {}", ErrnoString(errno));
        s->temp_ = buf.data();
        ::fchmod(s->fd_, 0644);
    }
    s->buffer_.reserve(size_t(1) << 20);
    return s;
}

std::unique_ptr<OutputStream> OutputStream::ToMemory(std::vector<uint8_t>* sink) {
    std::unique_ptr<OutputStream> s(new OutputStream());
    s->name_ = "<memory>";
    s->memory_ = sink;
    return s;
}

OutputStream::~OutputStream() {
    if (fd_ > 1) {
        ::close(fd_);
        if (!committed_ && !temp_.empty()) ::unlink(temp_.c_str());
    } else if (fd_ == 1 && !committed_) {
        // Best effort for stdout: push out what we have; errors are reported by Commit().
        if (!buffer_.empty()) (void)!::write(1, buffer_.data(), buffer_.size());
    }
}

void OutputStream::Write(const void* data, size_t n) {
    auto p = static_cast<const uint8_t*>(data);
    written_ += n;
    if (memory_) {
        memory_->insert(memory_->end(), p, p + n);
        return;
    }
    if (buffer_.size() + n > buffer_.capacity()) Flush();
    if (n >= buffer_.capacity()) {
        buffer_.assign(p, p + n);
        Flush();
        return;
    }
    buffer_.insert(buffer_.end(), p, p + n);
}

void OutputStream::Flush() {
    if (memory_ || buffer_.empty()) return;
    size_t done = 0;
    while (done < buffer_.size()) {
        ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
        if (n < 0) {
            if (errno == EINTR) continue;
            int err = errno;
            buffer_.clear();
            IoError({name_}, "write failed: {}", ErrnoString(err));
        }
        done += size_t(n);
    }
    buffer_.clear();
}

void OutputStream::Commit() {
    Flush();
    if (memory_ || committed_) {
        committed_ = true;
        return;
    }
    if (fd_ == 1 || temp_.empty()) {
        committed_ = true;
        return;
    }
    if (::fsync(fd_) != 0) IoError({name_}, "fsync failed: {}", ErrnoString(errno));
    if (::rename(temp_.c_str(), name_.c_str()) != 0)
        IoError({name_}, "cannot rename the finished output into place: {}", ErrnoString(errno));
    committed_ = true;
}

std::vector<uint8_t> ReadWholeFile(const std::string& path) {
    auto in = InputStream::Open(path);
    std::vector<uint8_t> bytes;
    uint8_t buf[65536];
    for (size_t n; (n = in->Read(buf, sizeof(buf))) > 0;)
        bytes.insert(bytes.end(), buf, buf + n);
    return bytes;
}

}  // namespace mebake::io
