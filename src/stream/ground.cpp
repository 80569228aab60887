#include "stream/ground.h"

#include <algorithm>

namespace mebake::stream {

namespace {
constexpr int kCells = 16;  // grid cells per side

double Side(const Vec3d& bbox_min, const Vec3d& bbox_max) {
    const Vec3d extent = bbox_max - bbox_min;
    return 3 * std::max({extent.x, extent.z, 1e-6 * Length(extent), 1e-9});
}

}  // namespace

double GroundPlaneArea(const Vec3d& bbox_min, const Vec3d& bbox_max) {
    const double side = Side(bbox_min, bbox_max);
    return side * side;
}

void WriteGroundPlane(const Vec3d& bbox_min, const Vec3d& bbox_max, io::MeshSink& sink) {
    const Vec3d extent = bbox_max - bbox_min;
    const double side = Side(bbox_min, bbox_max);
    const double cx = 0.5 * (bbox_min.x + bbox_max.x), cz = 0.5 * (bbox_min.z + bbox_max.z);
    // A hair below the lowest point, so the ground does not cut through the faces it touches.
    const double y = bbox_min.y - 1e-4 * std::max(Length(extent), 1e-9);
    io::MeshHeader header;
    header.source = kGroundSource;
    header.vertex_count = uint64_t(kCells + 1) * (kCells + 1);
    header.face_count = uint64_t(kCells) * kCells;
    sink.Begin(header);
    io::VertexBatch v;
    for (int j = 0; j <= kCells; ++j)
        for (int i = 0; i <= kCells; ++i)
            v.position.push_back(Vec3f(float(cx + side * (double(i) / kCells - 0.5)), float(y),
                                       float(cz + side * (double(j) / kCells - 0.5))));
    sink.Vertices(v);
    io::FaceBatch f;
    for (int j = 0; j < kCells; ++j)
        for (int i = 0; i < kCells; ++i) {
            const uint64_t a = uint64_t(j) * (kCells + 1) + uint64_t(i);
            const uint64_t b = a + 1, c = a + kCells + 1, d = c + 1;
            // Counter-clockwise seen from +Y: the normal points up.
            f.size.push_back(4);
            f.index.insert(f.index.end(), {a, c, d, b});
        }
    sink.Faces(f);
    io::MeshSummary summary;
    summary.vertex_count = header.vertex_count;
    summary.face_count = header.face_count;
    sink.End(summary);
}

}  // namespace mebake::stream
