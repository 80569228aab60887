// The streaming contract of mesh_stream.h, kept in one place for every reader: Begin()
// once, batch `first` indices that count what was delivered, and every pending vertex
// delivered before any face batch (a face only names vertices a sink has already seen).
// Readers fill their VertexBatch / FaceBatch and hand them here to flush.
#pragma once

#include <cstdint>

#include "io/mesh_stream.h"

namespace mebake::io {

class BatchEmitter {
public:
    explicit BatchEmitter(MeshSink& sink) : sink_(sink) {}

    void Begin(const MeshHeader& header) {
        if (begun_) return;
        begun_ = true;
        sink_.Begin(header);
    }
    bool begun() const { return begun_; }

    void FlushVertices(VertexBatch& verts) {
        if (verts.size() == 0) return;
        verts.first = vertices_sent_;
        sink_.Vertices(verts);
        vertices_sent_ += verts.size();
        verts.Clear();
    }
    void FlushFaces(VertexBatch& verts, FaceBatch& faces) {
        FlushVertices(verts);
        if (faces.count() == 0) return;
        faces.first = faces_sent_;
        sink_.Faces(faces);
        faces_sent_ += faces.count();
        faces.Clear();
    }

    uint64_t vertices_sent() const { return vertices_sent_; }
    uint64_t faces_sent() const { return faces_sent_; }

private:
    MeshSink& sink_;
    bool begun_ = false;
    uint64_t vertices_sent_ = 0, faces_sent_ = 0;
};

}  // namespace mebake::io
