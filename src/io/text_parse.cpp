// Line reading and number parsing for the text mesh readers (see text_parse.h).
#include "io/text_parse.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace mebake::io {

namespace {
// How much to ask Peek for at a time; lines are usually far shorter.
constexpr size_t kPeekChunk = size_t(64) << 10;
}  // namespace

bool TextLineReader::Next(std::string_view& line) {
    in_.Skip(pending_);
    pending_ = 0;
    joined_.clear();
    constexpr size_t kMax = InputStream::kMaxLine;
    bool straddles = false;
    for (;;) {
        auto avail = in_.Peek(kPeekChunk);
        if (avail.empty()) {
            if (!straddles)
                return false;
            line = joined_;
            break;
        }
        // Look no further than a line may reach (+1 for a '\r' before the '\n').
        size_t window = std::min(avail.size(), kMax + 2 - joined_.size());
        auto data = reinterpret_cast<const char*>(avail.data());
        auto nl = static_cast<const char*>(std::memchr(data, '\n', window));
        if (nl != nullptr) {
            size_t k = size_t(nl - data);
            if (!straddles) {
                line = std::string_view(data, k);
                pending_ = k + 1;
            } else {
                joined_.append(data, k);
                in_.Skip(k + 1);
                line = joined_;
            }
            break;
        }
        if (window < avail.size() || joined_.size() + window > kMax + 1) {
            InputError({in_.name(), FileLoc::kNone, line_ + 1},
                       "line longer than {} bytes; expected text (is this binary data?)", kMax);
        }
        joined_.append(data, window);
        in_.Skip(window);
        straddles = true;
    }
    ++line_;
    if (!line.empty() && line.back() == '\r')
        line.remove_suffix(1);
    // A UTF-8 byte order mark (Windows exporters) is not part of the first statement.
    if (line_ == 1 && line.substr(0, 3) == "\xEF\xBB\xBF")
        line.remove_prefix(3);
    if (line.size() > kMax) {
        InputError(Loc(), "line longer than {} bytes; expected text (is this binary data?)", kMax);
    }
    if (std::memchr(line.data(), '\0', line.size()) != nullptr)
        InputError(Loc(), "NUL byte in a text line; expected text (is this binary data?)");
    return true;
}

NumberStatus ParseTextFloat(std::string_view tok, float& out) {
    if (!tok.empty() && tok.front() == '+')
        tok.remove_prefix(1);
    if (tok.empty())
        return NumberStatus::Malformed;
    const char* end = tok.data() + tok.size();
    float v = 0;
    auto r = std::from_chars(tok.data(), end, v, std::chars_format::general);
    if (r.ptr != end)
        return NumberStatus::Malformed;
    if (r.ec == std::errc::result_out_of_range) {
        // Underflow is harmless (a signed zero); overflow is not a coordinate. A double
        // tells them apart unless it is out of range too, then the exponent's sign does.
        double d = 0;
        auto rd = std::from_chars(tok.data(), end, d, std::chars_format::general);
        bool tiny = false;
        if (rd.ec == std::errc()) {
            tiny = std::fabs(d) < 1.0;
        } else {
            size_t e = tok.find_first_of("eE");
            tiny = e != std::string_view::npos && e + 1 < tok.size() && tok[e + 1] == '-';
        }
        if (!tiny)
            return NumberStatus::OutOfRange;
        out = tok.front() == '-' ? -0.0f : 0.0f;
        return NumberStatus::Ok;
    }
    if (r.ec != std::errc())
        return NumberStatus::Malformed;
    if (!std::isfinite(v))
        return NumberStatus::NotFinite;
    out = v;
    return NumberStatus::Ok;
}

std::string QuoteToken(std::string_view tok) {
    constexpr size_t kShow = 40;
    std::string s = "'";
    for (char c : tok.substr(0, kShow)) {
        auto u = static_cast<unsigned char>(c);
        if (u >= 0x20 && u < 0x7f) {
            s += c;
        } else {
            s += fmt::format("\\x{:02x}", u);
        }
    }
    if (tok.size() > kShow)
        s += "...";
    s += "'";
    return s;
}

}  // namespace mebake::io
