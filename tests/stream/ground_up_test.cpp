// --ground on any up axis (stream/ground.h) and the up axis rule's names (stream/up_axis.h):
// for each of the six axis directions the ground's quads face up, lie a hair beyond the
// box's floor along up, and are centred under the box; +y keeps the plane of before.
#include "stream/ground.h"
#include "stream/up_axis.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace mebake::stream {
namespace {

struct Collect : io::MeshSink {
    std::vector<Vec3d> v;
    std::vector<std::vector<uint64_t>> faces;
    void Begin(const io::MeshHeader&) override {}
    void Vertices(const io::VertexBatch& b) override {
        for (const auto& p : b.position)
            v.push_back(Vec3d(p));
    }
    void Faces(const io::FaceBatch& b) override {
        size_t at = 0;
        for (uint32_t n : b.size) {
            faces.emplace_back(b.index.begin() + long(at), b.index.begin() + long(at + n));
            at += n;
        }
    }
    void End(const io::MeshSummary&) override {}
};

TEST(GroundUp, EveryAxisFacesUpUnderTheBox) {
    const Vec3d lo(-1, 2, 10), hi(3, 4, 16);
    for (const char* name : {"x", "-x", "y", "-y", "z", "-z"}) {
        const Vec3d up = *ParseAxis(name);
        EXPECT_EQ(ParseAxis(AxisName(up)), up) << name;
        Collect g;
        WriteGroundPlane(lo, hi, up, g);
        ASSERT_EQ(g.faces.size(), 256u) << name;
        const int a = std::abs(up.x) > 0 ? 0 : std::abs(up.y) > 0 ? 1 : 2;
        const double floor = up[a] > 0 ? lo[a] : hi[a];
        Vec3d centre(0, 0, 0), area(0, 0, 0);
        for (const Vec3d& p : g.v) {
            EXPECT_NEAR(p[a], floor, 1e-3) << name;
            EXPECT_LT(Dot(p, up), floor * up[a]) << name << ": not below the box's floor";
            centre += p * (1.0 / double(g.v.size()));
        }
        for (const auto& f : g.faces)
            area += Cross(g.v[f[1]] - g.v[f[0]], g.v[f[2]] - g.v[f[0]]) * 0.5 +
                    Cross(g.v[f[2]] - g.v[f[0]], g.v[f[3]] - g.v[f[0]]) * 0.5;
        // Facing up, with the area GroundPlaneArea reports.
        EXPECT_NEAR(Dot(area, up), GroundPlaneArea(lo, hi, up), 1e-3) << name;
        EXPECT_NEAR(Length(area), GroundPlaneArea(lo, hi, up), 1e-3) << name;
        for (int k = 0; k < 3; ++k) {
            if (k != a) {
                EXPECT_NEAR(centre[k], 0.5 * (lo[k] + hi[k]), 1e-4) << name;
            }
        }
    }
    EXPECT_FALSE(ParseAxis("w"));
    EXPECT_FALSE(ParseAxis("xy"));
}

}  // namespace
}  // namespace mebake::stream
