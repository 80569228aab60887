#include "core/error.h"

#include <cstring>

namespace mebake {

std::string FileLoc::ToString() const {
    std::string name = file.empty() ? std::string("<input>") : file;
    if (line != kNone) return fmt::format("{}: line {}", name, line);
    if (offset != kNone) return fmt::format("{}: byte {}", name, offset);
    return name;
}

void ThrowAt(ErrorKind kind, const FileLoc& loc, std::string_view message) {
    throw Error(kind, fmt::format("{}: {}", loc.ToString(), message));
}

std::string ErrnoString(int err) {
    char buf[256];
    // GNU strerror_r returns a pointer that may or may not be buf.
    const char* s = strerror_r(err, buf, sizeof(buf));
    return s;
}

}  // namespace mebake
