// The streaming mesh contract: a reader hands a sink batches of vertices and faces,
// never the whole mesh, so any size passes through in bounded memory.
//
// Order guarantees a sink can rely on:
//  - Begin() once, then any interleaving of Vertices() and Faces(), then End() once.
//  - Batches of each kind arrive in file order; `first` is the global index of the
//    batch's first element; vertex and face indices are 0-based and 64-bit.
//  - Every face index refers to a vertex that exists: PLY/OFF check against the
//    header's count, OBJ against the vertices read so far (forward references are an
//    input error). So a face may arrive before the vertex it names only for PLY files
//    whose face element precedes the vertex element.
//  - Polygons are not triangulated by readers (writers keep quads as quads);
//    Triangulate() below fans them. PLY tristrips arrive as triangles.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/vec.h"

namespace mebake::io {

enum class MeshFormat { Ply, Obj, Off, Stl };
enum class PlyEncoding { Ascii, BinaryLittleEndian, BinaryBigEndian };

constexpr uint64_t kUnknownCount = std::numeric_limits<uint64_t>::max();

struct MeshHeader {
    std::string source;                // file name or "<stdin>"
    MeshFormat format = MeshFormat::Ply;
    std::string encoding;              // "ascii", "binary_little_endian", ...
    uint64_t vertex_count = kUnknownCount;  // known up front for PLY and OFF
    uint64_t face_count = kUnknownCount;    // polygons (PLY face element, OFF)
    bool has_normals = false;
    bool has_colors = false;
    bool has_alpha = false;
    bool colors_are_float = false;     // source stored colours as float (else uchar)
    bool has_uvs = false;              // per-vertex texture coordinates
    std::vector<std::string> comments;        // PLY comment lines, OBJ/OFF header comments
    std::vector<std::string> obj_info;        // PLY obj_info lines
    std::vector<std::string> skipped;         // properties/elements read past, "vertex.confidence"
};

struct VertexBatch {
    uint64_t first = 0;
    std::vector<Vec3f> position;
    std::vector<Vec3f> normal;   // empty, or one per position
    std::vector<Vec3f> color;    // empty, or one per position; RGB in [0,1] (uchar/255)
    std::vector<float> alpha;    // empty, or one per position, in [0,1]
    std::vector<Vec2f> uv;       // empty, or one per position

    size_t size() const { return position.size(); }
    void Clear() {
        position.clear();
        normal.clear();
        color.clear();
        alpha.clear();
        uv.clear();
    }
};

struct FaceBatch {
    uint64_t first = 0;              // global index of the first polygon
    std::vector<uint32_t> size;      // corners per polygon (>= 3)
    std::vector<uint64_t> index;     // all corners, concatenated
    std::vector<uint32_t> material;  // empty, or per polygon: index into MeshSummary::materials

    size_t count() const { return size.size(); }
    void Clear() {
        size.clear();
        index.clear();
        material.clear();
    }
};

// What is only known at the end of the stream.
struct MeshSummary {
    uint64_t vertex_count = 0;
    uint64_t face_count = 0;            // polygons delivered
    uint64_t bytes_read = 0;
    std::vector<std::string> materials; // OBJ usemtl names, in order of first use
    std::vector<std::string> mtllibs;   // OBJ mtllib file names, as written
    std::vector<std::string> groups;    // OBJ g/o names, in order of first use
    uint64_t corner_uv_count = 0;       // OBJ vt records (per-corner, not per-vertex)
    uint64_t corner_normal_count = 0;   // OBJ vn records
};

class MeshSink {
public:
    virtual ~MeshSink() = default;
    virtual void Begin(const MeshHeader& header) = 0;
    virtual void Vertices(const VertexBatch& batch) = 0;
    virtual void Faces(const FaceBatch& batch) = 0;
    virtual void End(const MeshSummary& summary) = 0;
};

struct ReadOptions {
    size_t batch_vertices = size_t(1) << 16;  // elements per batch (memory per batch)
    size_t batch_faces = size_t(1) << 16;
};

// Fans each polygon of `faces` into triangles, appended to `tris` as index triples.
void Triangulate(const FaceBatch& faces, std::vector<uint64_t>& tris);

}  // namespace mebake::io
