// tools/reref: a reference's points re-addressed to another ingest of the same scan (other
// charts) must name the same surface points there: each point's triangle and barycentrics
// in the other ingest's tile give back the position the reference recorded. A point whose
// shading normal there is not the one recorded (its B was integrated over another
// hemisphere) is dropped and counted.
#include "io/chunk_file.h"
#include "run.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace mebake {
namespace {

namespace fs = std::filesystem;

nlohmann::json ReadJson(const fs::path& p) {
    std::ifstream in(p);
    return nlohmann::json::parse(in);
}

std::string Q(const fs::path& p) {
    return "'" + p.string() + "'";
}

TEST(Reref, PointsLandOnTheSameSurfacePointsInAnotherIngest) {
    const fs::path dir = fs::temp_directory_path() / ("mebake-reref-" + std::to_string(getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path reref = fs::path(MEBAKE_MKSCAN).parent_path() / "reref";
    ASSERT_EQ(e2e::Shell("'" + std::string(MEBAKE_MKSCAN) + "' -n 20000 --seed 3 -o " +
                         Q(dir / "s.ply") + " 2> /dev/null"),
              0);
    // A coarser light map lets the merge make larger charts: the same triangles, other tiles.
    ASSERT_EQ(e2e::Mebake("-q ingest " + Q(dir / "s.ply") + " -o " + Q(dir / "a.mebake")), 0);
    ASSERT_EQ(e2e::Mebake("-q ingest " + Q(dir / "s.ply") + " -o " + Q(dir / "b.mebake") +
                          " --lightmap-resolution 512"),
              0);
    const size_t charts_a = ReadJson(dir / "a.mebake" / "manifest.json")["charts"].size();
    const size_t charts_b = ReadJson(dir / "b.mebake" / "manifest.json")["charts"].size();
    ASSERT_NE(charts_a, charts_b) << "the two ingests must differ for the test to mean anything";
    ASSERT_EQ(e2e::Mebake("-q reference " + Q(dir / "a.mebake") +
                          " --points 60 --min-samples 4 --samples 4 -o " + Q(dir / "ref.json")),
              0);
    // Both ingests keep each triangle's corner order; the corners are rotated here so that
    // reref has to match them by vertex id.
    nlohmann::json before = ReadJson(dir / "ref.json");
    for (auto& p : before["points"]) {
        p["vertex_ids"] = {p["vertex_ids"][1], p["vertex_ids"][2], p["vertex_ids"][0]};
        p["barycentric"] = {p["barycentric"][1], p["barycentric"][2], p["barycentric"][0]};
    }
    std::ofstream(dir / "ref_rotated.json") << before.dump();
    ASSERT_EQ(e2e::Shell(Q(reref) + " " + Q(dir / "ref_rotated.json") + " " + Q(dir / "b.mebake") +
                         " -o " + Q(dir / "ref_b.json") + " 2> /dev/null"),
              0);

    const nlohmann::json after = ReadJson(dir / "ref_b.json");
    ASSERT_EQ(after["points"].size(), before["points"].size());  // no hole fill on the sphere
    size_t moved = 0;
    for (const auto& p : after["points"]) {
        char name[32];
        std::snprintf(name, sizeof(name), "c%06u.tile", p["chart"].get<unsigned>());
        const io::ChunkReader tile((dir / "b.mebake" / "tiles" / name).string(), io::Tag("TILE"), 1, 2);  // tile format 2 (stream/tile.h)
        const auto pos = tile.ReadArray<float>(io::Tag("VPOS"));
        const auto tris = tile.ReadArray<uint32_t>(io::Tag("TRIS"));
        const size_t t = p["triangle"].get<size_t>();
        ASSERT_LT(3 * t + 2, tris.size());
        for (int axis = 0; axis < 3; ++axis) {
            double x = 0;
            for (int k = 0; k < 3; ++k)
                x += p["barycentric"][k].get<double>() * pos[3 * tris[3 * t + k] + axis];
            EXPECT_NEAR(x, p["position"][axis].get<double>(), 1e-4) << "point " << p["face"];
        }
    }
    for (size_t i = 0; i < after["points"].size(); ++i)
        moved += after["points"][i]["chart"] != before["points"][i]["chart"] ||
                 after["points"][i]["triangle"] != before["points"][i]["triangle"];
    EXPECT_GT(moved, 0u);

    // On its own ingest every point keeps its normal; one whose recorded normal is turned
    // (as a chart border moved onto a crease would turn it) is dropped and counted.
    nlohmann::json turned = ReadJson(dir / "ref.json");
    const size_t n = turned["points"].size();
    auto& q = turned["points"][n / 2];
    const double nx = q["normal"][0], ny = q["normal"][1], nz = q["normal"][2];
    q["normal"] = {nx + 0.2 * ny, ny - 0.2 * nx, nz};  // about 11 degrees about z, or less
    q["normal"] = std::fabs(nz) > 0.98 ? nlohmann::json{nx + 0.2 * nz, ny, nz - 0.2 * nx} : q["normal"];
    std::ofstream(dir / "ref_turned.json") << turned.dump();
    const e2e::RunResult same = e2e::Capture(Q(reref) + " " + Q(dir / "ref.json") + " " +
                                             Q(dir / "a.mebake") + " -o " + Q(dir / "ref_a.json") + " 2>&1");
    ASSERT_EQ(same.code, 0) << same.out;
    EXPECT_EQ(ReadJson(dir / "ref_a.json")["points"].size(), n) << same.out;
    const e2e::RunResult one = e2e::Capture(Q(reref) + " " + Q(dir / "ref_turned.json") + " " +
                                            Q(dir / "a.mebake") + " -o " + Q(dir / "ref_t.json") + " 2>&1");
    ASSERT_EQ(one.code, 0) << one.out;
    EXPECT_EQ(ReadJson(dir / "ref_t.json")["points"].size(), n - 1) << one.out;
    EXPECT_NE(one.out.find("1 dropped for another shading normal"), std::string::npos) << one.out;

    // A directory that is not an ingest: non-zero exit, the path named.
    const e2e::RunResult bad = e2e::Capture(Q(reref) + " " + Q(dir / "ref.json") + " " +
                                            Q(dir / "nothing") + " -o " + Q(dir / "x.json") + " 2>&1");
    EXPECT_NE(bad.code, 0);
    EXPECT_NE(bad.out.find((dir / "nothing").string()), std::string::npos) << bad.out;
    fs::remove_all(dir);
}

}  // namespace
}  // namespace mebake
