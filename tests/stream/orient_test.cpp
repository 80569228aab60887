// Ingest's orientation pass (stream/orient.h): a closed mesh wound inwards comes out of
// ingest wound outwards (also when it spans several bricks), an outward one and an open
// one are left as read, a nearly closed one is turned, and an enclosure around another
// object (a room) is kept. Judged on the tiles: the signed volume of all their triangles.
// Also the up axis ingest detects (stream/up_axis.h) on two synthetic shapes.
#include "stream/ingest.h"
#include "stream/tile.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <string>
#include <tuple>
#include <unistd.h>
#include <vector>

namespace mebake::stream {
namespace {

namespace fs = std::filesystem;

struct Mesh {
    std::vector<Vec3d> v;
    std::vector<std::array<uint32_t, 3>> f;

    void Append(const Mesh& o) {
        const uint32_t base = uint32_t(v.size());
        v.insert(v.end(), o.v.begin(), o.v.end());
        for (auto t : o.f)
            f.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
    void Flip() {
        for (auto& t : f)
            std::swap(t[1], t[2]);
    }
};

// The surface of the cube [-1, 1]^3 as an n x n grid per side (shared vertices), wound
// outwards; `shape` maps each grid point (a sphere: normalize). Triangles whose centroid
// `keep` refuses are left out.
Mesh CubeGrid(
    int n, const std::function<Vec3d(Vec3d)>& shape,
    const std::function<bool(Vec3d)>& keep = [](Vec3d) { return true; }) {
    Mesh m;
    std::map<std::tuple<int, int, int>, uint32_t> ids;
    auto vertex = [&](int a, int b, int c) {
        auto [it, added] = ids.try_emplace({a, b, c}, uint32_t(m.v.size()));
        if (added)
            m.v.push_back(shape(Vec3d(a, b, c) * (1.0 / n)));
        return it->second;
    };
    for (int axis = 0; axis < 3; ++axis)
        for (int side : {-n, n})
            for (int i = -n; i < n; i += 2)
                for (int j = -n; j < n; j += 2) {
                    auto at = [&](int u, int w) {
                        int c[3];
                        c[axis] = side;
                        c[(axis + 1) % 3] = u;
                        c[(axis + 2) % 3] = w;
                        return vertex(c[0], c[1], c[2]);
                    };
                    const uint32_t q[4] = {at(i, j), at(i + 2, j), at(i + 2, j + 2), at(i, j + 2)};
                    for (auto t : {std::array<uint32_t, 3>{q[0], q[1], q[2]},
                                   std::array<uint32_t, 3>{q[0], q[2], q[3]}}) {
                        const Vec3d c = (m.v[t[0]] + m.v[t[1]] + m.v[t[2]]) * (1.0 / 3);
                        if (!keep(c))
                            continue;
                        Vec3d out(0, 0, 0);
                        (axis == 0 ? out.x : axis == 1 ? out.y : out.z) = side;
                        if (Dot(Cross(m.v[t[1]] - m.v[t[0]], m.v[t[2]] - m.v[t[0]]), out) < 0)
                            std::swap(t[1], t[2]);
                        m.f.push_back(t);
                    }
                }
    return m;
}

Vec3d OnSphere(Vec3d p) {
    return p * (1 / Length(p));
}

std::string TempPath(const std::string& name) {
    return (fs::temp_directory_path() /
            ("mebake_orient_" + std::to_string(::getpid()) + "_" + name))
        .string();
}

struct Result {
    Manifest manifest;
    double volume = 0;  // of all tiles' triangles, about the box centre
    std::string tiles;  // all tiles' bytes
};

Result IngestMesh(const Mesh& m, const std::string& name, uint64_t brick_faces = 400000,
                  int threads = 0) {
    const std::string ply = TempPath(name + ".ply"), dir = TempPath(name + ".mebake");
    {
        std::ofstream out(ply);
        out << "ply\nformat ascii 1.0\nelement vertex " << m.v.size()
            << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << m.f.size()
            << "\nproperty list uchar int vertex_indices\nend_header\n";
        for (const auto& p : m.v)
            out << p.x << ' ' << p.y << ' ' << p.z << '\n';
        for (const auto& t : m.f)
            out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
    }
    IngestOptions o;
    o.inputs = {ply};
    o.out_dir = dir;
    o.brick_faces = brick_faces;
    o.force = true;
    o.threads = threads;
    Result r;
    r.manifest = Ingest(o);
    const Vec3d centre = (r.manifest.bbox_min + r.manifest.bbox_max) * 0.5;
    for (uint32_t c = 0; c < r.manifest.charts.size(); ++c) {
        std::ifstream bytes(TilePath(dir, c), std::ios::binary);
        r.tiles.append(std::istreambuf_iterator<char>(bytes), {});
        const ChartTile t = ReadTile(TilePath(dir, c), TileParts::Mesh);
        for (const auto& tri : t.triangles) {
            Vec3d p[3];
            for (int k = 0; k < 3; ++k)
                p[k] = Vec3d(t.position[tri[size_t(k)]]) - centre;
            r.volume += Dot(p[0], Cross(p[1], p[2])) / 6;
        }
    }
    fs::remove(ply);
    fs::remove_all(dir);
    return r;
}

const auto kCube = [](Vec3d p) {
    return p;
};

TEST(Orient, ClosedCubeWoundInwardsComesOutOutwards) {
    Mesh cube = CubeGrid(8, kCube);
    cube.Flip();
    const Result r = IngestMesh(cube, "cube_in");
    EXPECT_EQ(r.manifest.orientation.components, 1u);
    EXPECT_EQ(r.manifest.orientation.flipped, 1u);
    EXPECT_EQ(r.manifest.orientation.flipped_triangles, cube.f.size());
    EXPECT_NEAR(r.volume, 8.0, 1e-3);  // the cube's volume, positive: outwards
}

TEST(Orient, OutwardCubeIsUntouched) {
    const Result r = IngestMesh(CubeGrid(8, kCube), "cube_out");
    EXPECT_EQ(r.manifest.orientation.flipped, 0u);
    EXPECT_NEAR(r.volume, 8.0, 1e-3);
}

TEST(Orient, OpenHemisphereIsLeftAsRead) {
    // A dome seen from outside or a bowl seen from inside: no inside geometry can name.
    Mesh half = CubeGrid(12, OnSphere, [](Vec3d c) { return c.z > 0; });
    half.Flip();
    const Result r = IngestMesh(half, "hemisphere_in");
    EXPECT_EQ(r.manifest.orientation.flipped, 0u);
    EXPECT_LT(r.volume, 0);  // still wound as read (the flux about the box centre is negative)
}

TEST(Orient, NearlyClosedSphereWoundInwardsIsTurned) {
    // A sphere missing a cap (a scan's hole): holes' projected area ~2 % of the surface.
    Mesh s = CubeGrid(12, OnSphere, [](Vec3d c) { return c.z < 0.85; });
    s.Flip();
    const Result r = IngestMesh(s, "open_sphere_in");
    EXPECT_EQ(r.manifest.orientation.flipped, 1u);
    EXPECT_GT(r.volume, 3.0);  // about 4/3 pi, less the cap's cone
}

TEST(Orient, InwardsSphereAcrossBricksIsTurnedAsOneComponent) {
    // 49K triangles in bricks of 20K faces: the sphere spans several bricks.
    Mesh s = CubeGrid(64, OnSphere);
    s.Flip();
    const Result r = IngestMesh(s, "sphere_bricks", 20000);
    ASSERT_GT(r.manifest.brick_count, 1u);
    EXPECT_EQ(r.manifest.orientation.components, 1u);
    EXPECT_EQ(r.manifest.orientation.flipped, 1u);
    EXPECT_EQ(r.manifest.orientation.flipped_triangles, s.f.size());
    EXPECT_NEAR(r.volume, 4 * M_PI / 3, 0.01);
    // The same tiles on one thread (the bricks are scanned two at a time otherwise).
    const Result one = IngestMesh(s, "sphere_bricks_1", 20000, 1);
    EXPECT_TRUE(one.tiles == r.tiles);
}

TEST(Orient, RoomAroundAnObjectIsKept) {
    // An inward box around an outward one: the room's walls are wound inwards on purpose.
    Mesh room = CubeGrid(4, [](Vec3d p) { return p * 4.0; });
    room.Flip();
    room.Append(CubeGrid(4, kCube));
    const Result r = IngestMesh(room, "room");
    EXPECT_EQ(r.manifest.orientation.components, 2u);
    EXPECT_EQ(r.manifest.orientation.flipped, 0u);
    EXPECT_EQ(r.manifest.orientation.nested_kept, 1u);
    EXPECT_NEAR(r.volume, 8.0 - 512.0, 0.1);
}

}  // namespace
}  // namespace mebake::stream

namespace mebake::stream {
namespace {

// The up axis at ingest (up_axis.h): a sphere on a pedestal, z-up, stands on +z; a cube
// stands equally on every side and keeps the default +y.
TEST(UpAxis, StatueOnAPedestalStandsOnItsBase) {
    Mesh statue = CubeGrid(6, [](Vec3d p) { return Vec3d(0.5 * p.x, 0.5 * p.y, 0.2 + 0.2 * p.z); });
    statue.Append(CubeGrid(12, [](Vec3d p) { return OnSphere(p) + Vec3d(0, 0, 1.4); }));
    EXPECT_EQ(IngestMesh(statue, "statue").manifest.up, Vec3d(0, 0, 1));
    EXPECT_EQ(IngestMesh(CubeGrid(4, kCube), "cube_up").manifest.up, Vec3d(0, 1, 0));
}

}  // namespace
}  // namespace mebake::stream
