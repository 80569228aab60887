// The PLY header (Turk 1994, "The PLY Polygon File Format"): the element and property
// declarations that say how to decode the body. Private to the PLY reader and writer.
#pragma once

#include "io/byte_stream.h"
#include "io/mesh_stream.h"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mebake::io {

// The eight PLY scalar types, named "char ... double" or "int8 ... float64".
enum class PlyType : uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

constexpr uint32_t PlyTypeSize(PlyType t) {
    constexpr uint32_t kSizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
    return kSizes[int(t)];
}
constexpr bool PlyTypeIsInteger(PlyType t) {
    return t != PlyType::Float32 && t != PlyType::Float64;
}
// The largest value of an integer type (maps integer colours to [0,1]); 1 for floats.
constexpr double PlyTypeMax(PlyType t) {
    constexpr double kMax[] = {127.0,        255.0,        32767.0, 65535.0,
                               2147483647.0, 4294967295.0, 1.0,     1.0};
    return kMax[int(t)];
}
// The smallest value of an integer type; 0 for floats.
constexpr double PlyTypeMin(PlyType t) {
    constexpr double kMin[] = {-128.0, 0.0, -32768.0, 0.0, -2147483648.0, 0.0, 0.0, 0.0};
    return kMin[int(t)];
}
// "char", "uchar", ... and their sized aliases; nullopt for anything else.
std::optional<PlyType> ParsePlyType(std::string_view name);

struct PlyProperty {
    std::string name;
    PlyType type = PlyType::Float32;  // the item type for a list
    bool is_list = false;
    PlyType count_type = PlyType::UInt8;  // lists only; always an integer type
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;  // as declared; untrusted until the body delivers it
    std::vector<PlyProperty> properties;
    uint64_t line = 0;  // header line of the declaration, for messages
};

struct PlyHeader {
    PlyEncoding encoding = PlyEncoding::Ascii;
    std::vector<PlyElement> elements;  // in file order
    std::vector<std::string> comments;
    std::vector<std::string> obj_info;
    uint64_t lines = 0;  // header lines, including "end_header"
};

// Reads and checks the header up to and including "end_header"; `in` is left at the
// first body byte. Throws InputError naming the line on anything malformed.
PlyHeader ParsePlyHeader(InputStream& in);

// The largest header we read before calling the input garbage.
constexpr uint64_t kMaxPlyHeaderBytes = uint64_t(4) << 20;

}  // namespace mebake::io
