// Parses a PLY header (Turk 1994, "The PLY Polygon File Format"): magic, format line,
// comment/obj_info lines, element and scalar/list property declarations, end_header.
// Everything is checked here so the body decoders can trust the declarations' shape
// (never their counts, which are only claims about the body).
#include "io/ply_header.h"

#include "core/error.h"

#include <charconv>
#include <cstring>
#include <unordered_set>

namespace mebake::io {

std::optional<PlyType> ParsePlyType(std::string_view n) {
    if (n == "char" || n == "int8")
        return PlyType::Int8;
    if (n == "uchar" || n == "uint8")
        return PlyType::UInt8;
    if (n == "short" || n == "int16")
        return PlyType::Int16;
    if (n == "ushort" || n == "uint16")
        return PlyType::UInt16;
    if (n == "int" || n == "int32")
        return PlyType::Int32;
    if (n == "uint" || n == "uint32")
        return PlyType::UInt32;
    if (n == "float" || n == "float32")
        return PlyType::Float32;
    if (n == "double" || n == "float64")
        return PlyType::Float64;
    return std::nullopt;
}

namespace {

// Splits on spaces and tabs.
std::vector<std::string_view> Words(std::string_view s) {
    std::vector<std::string_view> w;
    size_t i = 0;
    while (i < s.size()) {
        while (i < s.size() && (s[i] == ' ' || s[i] == '\t'))
            ++i;
        size_t j = i;
        while (j < s.size() && s[j] != ' ' && s[j] != '\t')
            ++j;
        if (j > i)
            w.push_back(s.substr(i, j - i));
        i = j;
    }
    return w;
}

// The text after the keyword, without the one separating blank.
std::string RestOfLine(std::string_view line, size_t keyword_len) {
    std::string_view rest = line.substr(keyword_len);
    if (!rest.empty() && (rest[0] == ' ' || rest[0] == '\t'))
        rest.remove_prefix(1);
    return std::string(rest);
}

// A printable excerpt of an unexpected line for messages.
std::string Excerpt(std::string_view s) {
    std::string out;
    for (char c : s.substr(0, 40)) {
        unsigned char u = static_cast<unsigned char>(c);
        out += (u >= 0x20 && u < 0x7f) ? c : '?';
    }
    if (s.size() > 40)
        out += "...";
    return out;
}

}  // namespace

PlyHeader ParsePlyHeader(InputStream& in) {
    PlyHeader h;
    const std::string& file = in.name();
    auto head = in.Peek(4);
    if (head.empty())
        InputError({file, 0}, "empty file, expected a PLY header starting with 'ply'");
    if (head.size() < 4 || std::memcmp(head.data(), "ply", 3) != 0 ||
        (head[3] != '\n' && head[3] != '\r'))
        InputError({file, 0}, "not a PLY file: expected the first line to be 'ply'");

    std::string line;
    uint64_t line_no = 0;
    bool have_format = false;
    std::unordered_set<std::string> property_names;  // of the current element
    for (;;) {
        if (in.offset() > kMaxPlyHeaderBytes)
            InputError({file, in.offset()}, "PLY header longer than {} bytes without 'end_header'",
                       kMaxPlyHeaderBytes);
        uint64_t at = in.offset();
        if (!in.ReadLine(line))
            InputError({file, at, line_no + 1}, "end of file inside the PLY header, expected "
                                                "'end_header'");
        ++line_no;
        FileLoc loc{file, at, line_no};
        auto w = Words(line);
        if (line_no == 1) {
            if (w.size() != 1 || w[0] != "ply")
                InputError(loc, "not a PLY file: expected the first line to be 'ply'");
            continue;
        }
        if (w.empty())
            continue;  // tolerated blank line
        const std::string_view kw = w[0];
        if (kw == "comment") {
            h.comments.push_back(RestOfLine(line, line.find("comment") + 7));
        } else if (kw == "obj_info") {
            h.obj_info.push_back(RestOfLine(line, line.find("obj_info") + 8));
        } else if (kw == "format") {
            if (have_format)
                InputError(loc, "second 'format' line in the PLY header");
            if (w.size() != 3)
                InputError(loc,
                           "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
            if (w[1] == "ascii") {
                h.encoding = PlyEncoding::Ascii;
            } else if (w[1] == "binary_little_endian") {
                h.encoding = PlyEncoding::BinaryLittleEndian;
            } else if (w[1] == "binary_big_endian") {
                h.encoding = PlyEncoding::BinaryBigEndian;
            } else {
                InputError(loc,
                           "unknown PLY format '{}', expected ascii, binary_little_endian or "
                           "binary_big_endian",
                           Excerpt(w[1]));
            }
            if (w[2] != "1.0" && w[2] != "1")
                InputError(loc, "unsupported PLY version '{}', expected 1.0", Excerpt(w[2]));
            have_format = true;
        } else if (kw == "element") {
            if (w.size() != 3)
                InputError(loc, "expected 'element <name> <count>'");
            PlyElement e;
            e.name = std::string(w[1]);
            e.line = line_no;
            auto [p, ec] = std::from_chars(w[2].data(), w[2].data() + w[2].size(), e.count);
            if (ec != std::errc() || p != w[2].data() + w[2].size())
                InputError(loc, "element '{}': count '{}' is not a non-negative integer below 2^64",
                           Excerpt(e.name), Excerpt(w[2]));
            for (const auto& other : h.elements)
                if (other.name == e.name &&
                    (e.name == "vertex" || e.name == "face" || e.name == "tristrips"))
                    InputError(loc, "second '{}' element in the PLY header", e.name);
            h.elements.push_back(std::move(e));
            property_names.clear();
        } else if (kw == "property") {
            if (h.elements.empty())
                InputError(loc, "'property' before any 'element' line in the PLY header");
            PlyProperty prop;
            if (w.size() >= 2 && w[1] == "list") {
                if (w.size() != 5)
                    InputError(loc, "expected 'property list <count type> <item type> <name>'");
                auto ct = ParsePlyType(w[2]);
                auto it = ParsePlyType(w[3]);
                if (!ct || !it)
                    InputError(loc,
                               "unknown PLY type '{}', expected char, uchar, short, ushort, "
                               "int, uint, float or double",
                               Excerpt(!ct ? w[2] : w[3]));
                if (!PlyTypeIsInteger(*ct))
                    InputError(loc, "list count type '{}' must be an integer type", w[2]);
                prop.is_list = true;
                prop.count_type = *ct;
                prop.type = *it;
                prop.name = std::string(w[4]);
            } else {
                if (w.size() != 3)
                    InputError(loc, "expected 'property <type> <name>'");
                auto t = ParsePlyType(w[1]);
                if (!t)
                    InputError(loc,
                               "unknown PLY type '{}', expected char, uchar, short, ushort, "
                               "int, uint, float or double",
                               Excerpt(w[1]));
                prop.type = *t;
                prop.name = std::string(w[2]);
            }
            if (!property_names.insert(prop.name).second)
                InputError(loc, "element '{}' declares property '{}' twice",
                           Excerpt(h.elements.back().name), Excerpt(prop.name));
            h.elements.back().properties.push_back(std::move(prop));
        } else if (kw == "end_header") {
            if (w.size() != 1)
                InputError(loc, "unexpected text after 'end_header'");
            if (!have_format)
                InputError(loc, "PLY header has no 'format' line before 'end_header'");
            h.lines = line_no;
            return h;
        } else {
            InputError(loc,
                       "unexpected '{}' in the PLY header, expected format, comment, "
                       "obj_info, element, property or end_header",
                       Excerpt(kw));
        }
    }
}

}  // namespace mebake::io
