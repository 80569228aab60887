// What `mebake info` reports about a mesh, gathered in one streaming pass with memory
// bounded independently of the mesh size (vertex positions needed for face areas are
// looked up through a bounded block cache over a temporary spill file).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "core/vec.h"
#include "io/mesh_stream.h"

namespace mebake::io {

struct MeshStats {
    MeshHeader header;
    MeshSummary summary;
    Vec3d bbox_min{}, bbox_max{};
    std::map<uint32_t, uint64_t> face_sizes;  // corners -> number of polygons
    uint64_t triangles = 0;                   // after fan triangulation
    uint64_t degenerate_faces = 0;            // a vertex index repeats within the face
    uint64_t zero_area_faces = 0;             // distinct indices, zero area (collinear)
    uint64_t unreferenced_vertices = 0;
    double surface_area = 0;
    double read_seconds = 0;
};

class MeshStatsSink : public MeshSink {
public:
    // temp_dir: where positions spill for face-area look-ups (empty: $TMPDIR or /tmp).
    // cache_bytes: memory for the look-up cache.
    explicit MeshStatsSink(std::string temp_dir = {}, size_t cache_bytes = size_t(16) << 20);
    ~MeshStatsSink() override;

    void Begin(const MeshHeader& header) override;
    void Vertices(const VertexBatch& batch) override;
    void Faces(const FaceBatch& batch) override;
    void End(const MeshSummary& summary) override;

    const MeshStats& stats() const { return stats_; }

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    MeshStats stats_;
};

}  // namespace mebake::io
