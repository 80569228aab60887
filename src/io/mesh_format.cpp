#include "io/mesh_format.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>

#include "core/error.h"

namespace mebake::io {

std::optional<MeshFormat> ParseFormatName(const std::string& name) {
    std::string n = name;
    for (auto& c : n) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (!n.empty() && n[0] == '.') n.erase(0, 1);
    if (n == "ply") return MeshFormat::Ply;
    if (n == "obj") return MeshFormat::Obj;
    if (n == "off") return MeshFormat::Off;
    if (n == "stl") return MeshFormat::Stl;
    return std::nullopt;
}

const char* FormatName(MeshFormat format) {
    switch (format) {
    case MeshFormat::Ply: return "ply";
    case MeshFormat::Obj: return "obj";
    case MeshFormat::Off: return "off";
    case MeshFormat::Stl: return "stl";
    }
    return "?";
}

std::optional<MeshFormat> FormatFromPath(const std::string& path) {
    if (path == "-") return std::nullopt;
    return ParseFormatName(std::filesystem::path(path).extension().string());
}

namespace {
bool StartsWith(std::span<const uint8_t> b, const char* s) {
    size_t n = std::strlen(s);
    return b.size() >= n && std::memcmp(b.data(), s, n) == 0;
}
}  // namespace

MeshFormat DetectFormat(InputStream& in, const std::string& path,
                        std::optional<MeshFormat> forced) {
    if (forced) return *forced;
    if (auto f = FormatFromPath(path)) return *f;
    auto head = in.Peek(512);
    if (head.empty()) InputError({in.name(), 0}, "empty input, expected a mesh");
    if (StartsWith(head, "ply")) return MeshFormat::Ply;
    if (StartsWith(head, "OFF") || StartsWith(head, "NOFF") || StartsWith(head, "COFF") ||
        StartsWith(head, "CNOFF"))
        return MeshFormat::Off;
    // A binary STL may also start with "solid"; it then has no "facet" soon after.
    if (StartsWith(head, "solid")) {
        std::string_view text(reinterpret_cast<const char*>(head.data()), head.size());
        if (text.find("facet") != std::string_view::npos) return MeshFormat::Stl;
    }
    // OBJ: text whose first statements are OBJ keywords.
    std::string_view text(reinterpret_cast<const char*>(head.data()), head.size());
    for (const char* kw : {"v ", "vn ", "vt ", "f ", "o ", "g ", "mtllib ", "usemtl ", "#", "s "})
        if (text.rfind(kw, 0) == 0) return MeshFormat::Obj;
    // An 80-byte header then a triangle count that matches the stream size is binary STL;
    // on a pipe we cannot check the size, so accept any non-text header of 84+ bytes.
    if (head.size() >= 84 && std::any_of(head.begin(), head.begin() + 84,
                                         [](uint8_t c) { return c == 0 || c >= 0x80; }))
        return MeshFormat::Stl;
    InputError({in.name(), 0},
               "cannot tell the mesh format from the first bytes; name the file with its "
               "extension or pass --format ply|obj|off|stl");
}

void ReadMesh(InputStream& in, MeshFormat format, MeshSink& sink, const ReadOptions& opt) {
    switch (format) {
    case MeshFormat::Ply: return ReadPly(in, sink, opt);
    case MeshFormat::Obj: return ReadObj(in, sink, opt);
    case MeshFormat::Off: return ReadOff(in, sink, opt);
    case MeshFormat::Stl: return ReadStl(in, sink, opt);
    }
}

std::unique_ptr<MeshSink> MakeMeshWriter(OutputStream& out, MeshFormat format,
                                         const WriteOptions& opt) {
    switch (format) {
    case MeshFormat::Ply: return MakePlyWriter(out, opt);
    case MeshFormat::Obj: return MakeObjWriter(out, opt);
    default:
        UsageError("cannot write {} files; mebake writes ply and obj", FormatName(format));
    }
}

void Triangulate(const FaceBatch& faces, std::vector<uint64_t>& tris) {
    size_t at = 0;
    for (uint32_t n : faces.size) {
        for (uint32_t k = 1; k + 1 < n; ++k) {
            tris.push_back(faces.index[at]);
            tris.push_back(faces.index[at + k]);
            tris.push_back(faces.index[at + k + 1]);
        }
        at += n;
    }
}

}  // namespace mebake::io
