// Choosing a format and opening readers and writers for it.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "io/byte_stream.h"
#include "io/mesh_stream.h"

namespace mebake::io {

// "ply", "obj", "off", "stl" (case-insensitive) -> format; nullopt otherwise.
std::optional<MeshFormat> ParseFormatName(const std::string& name);
const char* FormatName(MeshFormat format);

// The format of a file from its extension; nullopt for "-" or an unknown extension.
std::optional<MeshFormat> FormatFromPath(const std::string& path);

// The format of `in`: `forced` if given, else the path's extension, else sniffed from
// the first bytes (pipes). Throws Error(Input) naming the stream when it cannot tell.
MeshFormat DetectFormat(InputStream& in, const std::string& path,
                        std::optional<MeshFormat> forced);

// Streams the whole mesh from `in` into `sink`. Throws Error(Input) with the stream's
// name and the byte offset or line on malformed data.
void ReadMesh(InputStream& in, MeshFormat format, MeshSink& sink, const ReadOptions& opt = {});

// Each reader, for tests and fuzzers.
void ReadPly(InputStream& in, MeshSink& sink, const ReadOptions& opt);
void ReadObj(InputStream& in, MeshSink& sink, const ReadOptions& opt);
void ReadOff(InputStream& in, MeshSink& sink, const ReadOptions& opt);
void ReadStl(InputStream& in, MeshSink& sink, const ReadOptions& opt);

struct WriteOptions {
    PlyEncoding ply_encoding = PlyEncoding::BinaryLittleEndian;
    bool normals = true;        // write normals when the input has them
    bool colors = true;         // write colours when the input has them
    bool float_colors = false;  // PLY: float colours instead of uchar
    bool uvs = true;            // write per-vertex uvs when the input has them
    // Where writers spill when they must see everything before writing (a PLY header
    // needs counts an OBJ stream only knows at its end). Empty: $TMPDIR or /tmp.
    std::string temp_dir;
};

// A sink that writes the mesh to `out` as it streams by; Commit()s `out` in End().
std::unique_ptr<MeshSink> MakePlyWriter(OutputStream& out, const WriteOptions& opt);
std::unique_ptr<MeshSink> MakeObjWriter(OutputStream& out, const WriteOptions& opt);
std::unique_ptr<MeshSink> MakeMeshWriter(OutputStream& out, MeshFormat format,
                                         const WriteOptions& opt);

}  // namespace mebake::io
