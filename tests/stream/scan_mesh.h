// Test helper: a whole scan (any format io reads) as one TriMesh, polygons fanned into
// triangles, ids = input indices, material 0. nullopt when the file is absent.
#pragma once

#include "io/byte_stream.h"
#include "io/mesh_format.h"
#include "io/mesh_stream.h"
#include "stream/trimesh.h"

#include <filesystem>
#include <optional>
#include <string>

namespace mebake::stream::testing {

inline std::optional<TriMesh> LoadScan(const std::string& path) {
    if (!std::filesystem::exists(path))
        return std::nullopt;
    struct Sink : io::MeshSink {
        TriMesh m;
        std::vector<uint64_t> tris;
        void Begin(const io::MeshHeader&) override {}
        void Vertices(const io::VertexBatch& b) override {
            for (size_t k = 0; k < b.size(); ++k) {
                m.position.push_back(b.position[k]);
                m.vertex_id.push_back(b.first + k);
            }
        }
        void Faces(const io::FaceBatch& b) override {
            tris.clear();
            io::Triangulate(b, tris);
            for (size_t k = 0; k + 2 < tris.size(); k += 3) {
                m.triangles.push_back(
                    {uint32_t(tris[k]), uint32_t(tris[k + 1]), uint32_t(tris[k + 2])});
                m.face_id.push_back(m.face_id.size());
                m.material.push_back(0);
            }
        }
        void End(const io::MeshSummary&) override {}
    } sink;
    auto in = io::InputStream::Open(path);
    io::ReadMesh(*in, io::DetectFormat(*in, path, std::nullopt), sink);
    return std::move(sink.m);
}

}  // namespace mebake::stream::testing
