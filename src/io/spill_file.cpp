#include "io/spill_file.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "core/error.h"
#include "core/temp_file.h"

namespace mebake::io {

namespace {
constexpr size_t kBufferSize = size_t(1) << 20;
}

SpillFile::SpillFile(const std::string& dir, std::string purpose)
    : dir_(TemporaryDirectory(dir)), purpose_(std::move(purpose)), fd_(OpenTemporaryFile(dir, purpose_)) {
    buffer_.reserve(kBufferSize);
}

SpillFile::~SpillFile() {
    if (fd_ >= 0) ::close(fd_);
}

void SpillFile::Flush() {
    const uint8_t* p = buffer_.data();
    size_t n = buffer_.size();
    while (n > 0) {
        ssize_t k = ::write(fd_, p, n);
        if (k < 0 && errno == EINTR) continue;
        if (k < 0)
            IoError({dir_}, "cannot write the {}'s temporary file: {}", purpose_, ErrnoString(errno));
        p += k;
        n -= size_t(k);
    }
    buffer_.clear();
}

void SpillFile::Write(const void* data, size_t n) {
    const auto* p = static_cast<const uint8_t*>(data);
    size_ += n;
    while (n > 0) {
        size_t k = std::min(n, kBufferSize - buffer_.size());
        buffer_.insert(buffer_.end(), p, p + k);
        p += k;
        n -= k;
        if (buffer_.size() == kBufferSize) Flush();
    }
}

void SpillFile::CopyTo(OutputStream& out) {
    Flush();
    if (::lseek(fd_, 0, SEEK_SET) != 0)
        IoError({dir_}, "cannot rewind the {}'s temporary file: {}", purpose_, ErrnoString(errno));
    buffer_.resize(kBufferSize);
    uint64_t left = size_;
    while (left > 0) {
        ssize_t n = ::read(fd_, buffer_.data(), size_t(std::min<uint64_t>(left, kBufferSize)));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            IoError({dir_}, "cannot read back the {}'s temporary file: {}", purpose_,
                    n < 0 ? ErrnoString(errno) : std::string("it is shorter than written"));
        out.Write(buffer_.data(), size_t(n));
        left -= uint64_t(n);
    }
    buffer_.clear();
    // Further writes append after what was copied.
    if (::lseek(fd_, 0, SEEK_END) < 0)
        IoError({dir_}, "cannot seek the {}'s temporary file: {}", purpose_, ErrnoString(errno));
}

}  // namespace mebake::io
