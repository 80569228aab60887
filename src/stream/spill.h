// Ingest pass 1: the vertex and face spill. Every input mesh streams through a MeshSink
// that appends vertex positions, colours and triangulated faces to flat files in the bake
// directory, so later passes can look vertices up by global index without holding the
// mesh. Memory: one page cache per file, independent of the mesh size.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/paged_file.h"
#include "core/vec.h"
#include "io/mesh_stream.h"

namespace mebake::stream {

// One triangle as spilled: global vertex indices and a packed material
// (input mesh index << 16 | the mesh's own material index).
struct SpillFace {
    uint64_t v[3];
    uint32_t material;
    uint32_t reserved;
};
static_assert(sizeof(SpillFace) == 32);

// RGBA8 per vertex; alpha 0 means "no colour" (the material's albedo applies).
struct SpillColor {
    uint8_t r, g, b, a;
};

struct SpillInput {
    std::string source;      // path or "<stdin>"
    uint64_t first_vertex = 0, vertex_count = 0;
    uint64_t first_face = 0, face_count = 0;  // triangles
    uint64_t bytes_read = 0;
    bool has_colors = false;
    std::vector<std::string> materials;       // the mesh's own material names
    std::vector<std::string> mtllibs;
};

struct SpillResult {
    std::vector<SpillInput> inputs;
    uint64_t vertex_count = 0, face_count = 0;
    Vec3d bbox_min{1e300, 1e300, 1e300}, bbox_max{-1e300, -1e300, -1e300};
};

class Spill {
public:
    // Files: <dir>/vertices.bin (Vec3f), <dir>/colors.bin (SpillColor), <dir>/faces.bin.
    Spill(const std::string& dir, size_t cache_bytes);
    ~Spill();

    // A sink for the next input mesh; valid until the next call.
    io::MeshSink& BeginInput(const std::string& source);
    // Flushes all files; returns what was spilled.
    const SpillResult& Finish();
    // What was spilled so far (counts, bounding box).
    const SpillResult& result() const { return result_; }

    static std::string VerticesPath(const std::string& dir) { return dir + "/vertices.bin"; }
    static std::string ColorsPath(const std::string& dir) { return dir + "/colors.bin"; }
    static std::string FacesPath(const std::string& dir) { return dir + "/faces.bin"; }

private:
    class Sink;
    std::unique_ptr<DiskArray<Vec3f>> vertices_;
    std::unique_ptr<DiskArray<SpillColor>> colors_;
    std::unique_ptr<DiskArray<SpillFace>> faces_;
    std::unique_ptr<Sink> sink_;
    SpillResult result_;
};

}  // namespace mebake::stream
