// Line and number scanning shared by the text mesh readers (OBJ, OFF, ASCII STL).
// Lines are handed out as views into the stream's buffer when they fit (no copy, no
// allocation); a line that straddles the buffer is assembled in one reused string.
// Numbers go through std::from_chars: locale-free, exact rounding, no iostreams.
#pragma once

#include "core/error.h"
#include "io/byte_stream.h"

#include <charconv>
#include <cstdint>
#include <string>
#include <string_view>

namespace mebake::io {

// Reads a text stream line by line. A NUL byte or a line longer than
// InputStream::kMaxLine is an input error naming the line ("binary data?").
class TextLineReader {
public:
    explicit TextLineReader(InputStream& in) : in_(in) {}
    ~TextLineReader() { in_.Skip(pending_); }
    TextLineReader(const TextLineReader&) = delete;
    TextLineReader& operator=(const TextLineReader&) = delete;

    // The next line without "\n" / "\r\n", valid until the next call. False at the end.
    bool Next(std::string_view& line);

    uint64_t line_number() const { return line_; }  // 1-based, of the last line returned
    // Where the last line returned sits, for errors.
    FileLoc Loc() const { return {in_.name(), FileLoc::kNone, line_}; }
    InputStream& stream() { return in_; }
    // Bytes consumed including the last line returned.
    uint64_t offset() const { return in_.offset() + pending_; }

private:
    InputStream& in_;
    size_t pending_ = 0;  // bytes of the last line still to Skip (it is viewed in place)
    std::string joined_;  // a line that straddled the buffer
    uint64_t line_ = 0;
};

inline bool IsTextSpace(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

inline std::string_view TrimText(std::string_view s) {
    while (!s.empty() && IsTextSpace(s.front()))
        s.remove_prefix(1);
    while (!s.empty() && IsTextSpace(s.back()))
        s.remove_suffix(1);
    return s;
}

// Drops a '#' comment and everything after it.
inline std::string_view StripComment(std::string_view s) {
    size_t hash = s.find('#');
    return hash == std::string_view::npos ? s : s.substr(0, hash);
}

// The next whitespace-separated token of `rest` (empty when none), advancing `rest`.
inline std::string_view NextToken(std::string_view& rest) {
    size_t i = 0, n = rest.size();
    while (i < n && IsTextSpace(rest[i]))
        ++i;
    size_t start = i;
    while (i < n && !IsTextSpace(rest[i]))
        ++i;
    std::string_view tok = rest.substr(start, i - start);
    rest.remove_prefix(i);
    return tok;
}

// Case-insensitive ASCII comparison (ASCII STL keywords come in either case).
inline bool EqualsNoCase(std::string_view a, std::string_view b) {
    if (a.size() != b.size())
        return false;
    for (size_t i = 0; i < a.size(); ++i) {
        char x = a[i], y = b[i];
        if (x >= 'A' && x <= 'Z')
            x = char(x - 'A' + 'a');
        if (y >= 'A' && y <= 'Z')
            y = char(y - 'A' + 'a');
        if (x != y)
            return false;
    }
    return true;
}

enum class NumberStatus { Ok, Malformed, NotFinite, OutOfRange };

// Parses all of `tok` as a float ("1", "-2.5e3", "+.5"). Values too small for a float
// become a signed zero; "nan"/"inf" and values too large are reported, not returned.
NumberStatus ParseTextFloat(std::string_view tok, float& out);

// Parses all of `tok` as a decimal integer with an optional sign.
inline bool ParseTextInt(std::string_view tok, int64_t& out) {
    if (!tok.empty() && tok.front() == '+')
        tok.remove_prefix(1);
    if (tok.empty())
        return false;
    auto r = std::from_chars(tok.data(), tok.data() + tok.size(), out);
    return r.ec == std::errc() && r.ptr == tok.data() + tok.size();
}

// "what" for messages: the token quoted and shortened so garbage stays readable.
std::string QuoteToken(std::string_view tok);

}  // namespace mebake::io
