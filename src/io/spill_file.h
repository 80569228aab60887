// An anonymous temporary file (unlinked as soon as it is created, so nothing is left
// behind whatever happens): written sequentially through a buffer, then copied out
// whole. Writers use it when they must see everything before they can write (a PLY
// header needs counts, a .glb its buffer sizes, an OBJ faces after their vertices).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "io/byte_stream.h"

namespace mebake::io {

class SpillFile {
public:
    // `dir` empty: $TMPDIR, else /tmp. `purpose` names the file in error messages.
    SpillFile(const std::string& dir, std::string purpose);
    ~SpillFile();
    SpillFile(const SpillFile&) = delete;
    SpillFile& operator=(const SpillFile&) = delete;

    void Write(const void* data, size_t n);
    uint64_t size() const { return size_; }
    // Appends everything written so far to `out`.
    void CopyTo(OutputStream& out);

private:
    void Flush();
    std::string dir_, purpose_;
    int fd_ = -1;
    std::vector<uint8_t> buffer_;
    uint64_t size_ = 0;
};

}  // namespace mebake::io
