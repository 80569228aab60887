// Errors for bad input or a bad environment, as opposed to bugs (see check.h).
// An Error names where it happened (file, and byte offset or line) and what was expected;
// the CLI turns it into a message on stderr and a non-zero exit code in one place.
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace mebake {

enum class ErrorKind {
    Input,      // malformed or unsupported input data (exit 1)
    Io,         // the operating system refused: missing file, disk full, permissions (exit 1)
    Corrupt,    // a file mebake wrote fails its checksum or structure checks (exit 1)
    Usage,      // options that do not fit together (exit 2)
    Cancelled,  // interrupted by a signal or a limit; work so far is kept (exit 130)
};

// Where in a file something went wrong. offset and line are optional (kNone).
struct FileLoc {
    static constexpr uint64_t kNone = ~uint64_t(0);
    std::string file;
    uint64_t offset = kNone;  // byte offset from the start of the stream
    uint64_t line = kNone;    // 1-based line number, for text formats

    std::string ToString() const;  // "file: line 12" / "file: byte 4096" / "file"
};

class Error : public std::runtime_error {
public:
    Error(ErrorKind kind, const std::string& message)
        : std::runtime_error(message), kind_(kind) {}
    ErrorKind kind() const { return kind_; }

private:
    ErrorKind kind_;
};

// Throws Error(kind, "<loc>: <message>").
[[noreturn]] void ThrowAt(ErrorKind kind, const FileLoc& loc, std::string_view message);

template <typename... Args>
[[noreturn]] void InputError(const FileLoc& loc, fmt::format_string<Args...> f, Args&&... args) {
    ThrowAt(ErrorKind::Input, loc, fmt::format(f, std::forward<Args>(args)...));
}

template <typename... Args>
[[noreturn]] void IoError(const FileLoc& loc, fmt::format_string<Args...> f, Args&&... args) {
    ThrowAt(ErrorKind::Io, loc, fmt::format(f, std::forward<Args>(args)...));
}

template <typename... Args>
[[noreturn]] void CorruptError(const FileLoc& loc, fmt::format_string<Args...> f,
                               Args&&... args) {
    ThrowAt(ErrorKind::Corrupt, loc, fmt::format(f, std::forward<Args>(args)...));
}

template <typename... Args>
[[noreturn]] void UsageError(fmt::format_string<Args...> f, Args&&... args) {
    throw Error(ErrorKind::Usage, fmt::format(f, std::forward<Args>(args)...));
}

// "strerror(errno)" as a string, thread-safe.
std::string ErrnoString(int err);

}  // namespace mebake
