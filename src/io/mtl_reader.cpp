#include "io/mtl_reader.h"

#include <charconv>
#include <cmath>
#include <string_view>

#include "core/error.h"
#include "io/byte_stream.h"

namespace mebake::io {

namespace {
std::string_view NextToken(std::string_view& s) {
    size_t b = s.find_first_not_of(" \t");
    if (b == std::string_view::npos) {
        s = {};
        return {};
    }
    s.remove_prefix(b);
    size_t e = s.find_first_of(" \t");
    std::string_view tok = s.substr(0, e);
    s.remove_prefix(e == std::string_view::npos ? s.size() : e);
    return tok;
}
}  // namespace

std::vector<MtlMaterial> ReadMtl(const std::string& path) {
    auto in = InputStream::Open(path);
    std::vector<MtlMaterial> out;
    std::string line;
    uint64_t line_no = 0;
    auto number = [&](std::string_view& rest) {
        std::string_view tok = NextToken(rest);
        float v = 0;
        auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
        if (tok.empty() || ec != std::errc() || p != tok.data() + tok.size() || !std::isfinite(v))
            InputError({path, FileLoc::kNone, line_no}, "expected a number, found '{}'", tok);
        return v;
    };
    auto color = [&](std::string_view& rest) {
        Vec3f c;
        c.x = number(rest);
        // "Kd 0.5" means grey: one value stands for all three.
        std::string_view probe = rest;
        if (NextToken(probe).empty()) return Vec3f(c.x, c.x, c.x);
        c.y = number(rest);
        c.z = number(rest);
        return c;
    };
    while (in->ReadLine(line)) {
        ++line_no;
        std::string_view rest(line);
        if (size_t hash = rest.find('#'); hash != std::string_view::npos) rest = rest.substr(0, hash);
        std::string_view key = NextToken(rest);
        if (key.empty()) continue;
        if (key == "newmtl") {
            MtlMaterial m;
            size_t b = rest.find_first_not_of(" \t");
            m.name = b == std::string_view::npos ? "" : std::string(rest.substr(b));
            while (!m.name.empty() && (m.name.back() == ' ' || m.name.back() == '\t'))
                m.name.pop_back();
            out.push_back(std::move(m));
            continue;
        }
        if (out.empty()) continue;  // statements before the first newmtl mean nothing
        MtlMaterial& m = out.back();
        if (key == "Kd") m.kd = color(rest);
        else if (key == "Ka") m.ka = color(rest);
        else if (key == "Ke") m.ke = color(rest);
        else if (key == "Ks") m.ks = color(rest);
        else if (key == "Ns") m.ns = number(rest);
    }
    return out;
}

}  // namespace mebake::io
