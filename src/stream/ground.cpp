#include "stream/ground.h"

#include <algorithm>
#include <cmath>

namespace mebake::stream {

namespace {
constexpr int kCells = 16;  // grid cells per side

// The up axis (0, 1, 2) of an axis vector, and the two axes of the plane across it in the
// order (z, x) for y, (y, z) for x, (x, y) for z: the first is i, the second j of the grid.
struct Frame {
    int up = 1, i = 0, j = 2;
    bool positive = true;
    explicit Frame(const Vec3d& up_dir) {
        for (int a = 0; a < 3; ++a)
            if (std::abs(up_dir[a]) > std::abs(up_dir[up]))
                up = a;
        positive = up_dir[up] > 0;
        i = (up + 2) % 3;
        j = (up + 1) % 3;
    }
};

double Side(const Vec3d& bbox_min, const Vec3d& bbox_max, const Frame& f) {
    const Vec3d extent = bbox_max - bbox_min;
    return 3 * std::max({extent[f.i], extent[f.j], 1e-6 * Length(extent), 1e-9});
}

}  // namespace

double GroundPlaneArea(const Vec3d& bbox_min, const Vec3d& bbox_max, const Vec3d& up) {
    const double side = Side(bbox_min, bbox_max, Frame(up));
    return side * side;
}

void WriteGroundPlane(const Vec3d& bbox_min, const Vec3d& bbox_max, const Vec3d& up,
                      io::MeshSink& sink) {
    const Frame f(up);
    const Vec3d extent = bbox_max - bbox_min;
    const double side = Side(bbox_min, bbox_max, f);
    const double ci = 0.5 * (bbox_min[f.i] + bbox_max[f.i]);
    const double cj = 0.5 * (bbox_min[f.j] + bbox_max[f.j]);
    // A hair below the lowest point, so the ground does not cut through the faces it touches.
    const double gap = 1e-4 * std::max(Length(extent), 1e-9);
    const double level = f.positive ? bbox_min[f.up] - gap : bbox_max[f.up] + gap;
    io::MeshHeader header;
    header.source = kGroundSource;
    header.vertex_count = uint64_t(kCells + 1) * (kCells + 1);
    header.face_count = uint64_t(kCells) * kCells;
    sink.Begin(header);
    io::VertexBatch v;
    for (int j = 0; j <= kCells; ++j)
        for (int i = 0; i <= kCells; ++i) {
            Vec3d p;
            p[f.i] = ci + side * (double(i) / kCells - 0.5);
            p[f.j] = cj + side * (double(j) / kCells - 0.5);
            p[f.up] = level;
            v.position.push_back(Vec3f(p));
        }
    sink.Vertices(v);
    io::FaceBatch faces;
    for (int j = 0; j < kCells; ++j)
        for (int i = 0; i < kCells; ++i) {
            const uint64_t a = uint64_t(j) * (kCells + 1) + uint64_t(i);
            const uint64_t b = a + 1, c = a + kCells + 1, d = c + 1;
            // (i, j, up) is a left-handed frame: a c d b turns counter-clockwise seen from up.
            faces.size.push_back(4);
            if (f.positive)
                faces.index.insert(faces.index.end(), {a, c, d, b});
            else
                faces.index.insert(faces.index.end(), {a, b, d, c});
        }
    sink.Faces(faces);
    io::MeshSummary summary;
    summary.vertex_count = header.vertex_count;
    summary.face_count = header.face_count;
    sink.End(summary);
}

}  // namespace mebake::stream
