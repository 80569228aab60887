// The real mebake binary on real data: `info` counts every shared scan as the data README
// says, `convert` round-trips through pipes, bad input and bad usage give clear errors
// and the documented exit codes, and a small bake runs end to end.
#include "run.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;

using mebake::e2e::Capture;

const std::string kBin = MEBAKE_BINARY;
const std::string kData = MEBAKE_SHARED_DATA;

std::string Scan(const char* name) {
    return kData + "/scans/" + name;
}

TEST(Cli, InfoCountsEverySharedScan) {
    if (!fs::exists(kData))
        GTEST_SKIP() << "../shared/data is absent";
    struct Case {
        const char* file;
        uint64_t faces;
    };
    // Triangle counts from ../shared/data/README.md.
    const Case cases[] = {{"igea.ply", 268686},          {"nefertiti.obj", 99938},
                          {"horse.ply", 96966},          {"lucy.ply", 99970},
                          {"pepper.ply", 29956},         {"turbineblade.ply", 199034},
                          {"bun_zipper.ply", 69451},     {"bun_zipper_res2.ply", 16301},
                          {"bun_zipper_res3.ply", 3851}, {"bun_zipper_res4.ply", 948}};
    for (const auto& c : cases) {
        auto r = Capture(kBin + " info --json " + Scan(c.file));
        ASSERT_EQ(r.code, 0) << c.file;
        auto j = nlohmann::json::parse(r.out);
        EXPECT_EQ(j["triangles"].get<uint64_t>(), c.faces) << c.file;
    }
    auto j = nlohmann::json::parse(Capture(kBin + " info --json " + Scan("bun_zipper.ply")).out);
    EXPECT_EQ(j["vertices"].get<uint64_t>(), 35947u);
    EXPECT_EQ(j["unreferenced_vertices"].get<uint64_t>(), 1113u);
}

TEST(Cli, InfoReadsEverySceneMesh) {
    if (!fs::exists(kData))
        GTEST_SKIP() << "../shared/data is absent";
    int n = 0;
    for (const auto& e : fs::recursive_directory_iterator(kData + "/scenes")) {
        if (e.path().extension() != ".obj")
            continue;
        auto r = Capture(kBin + " info --json '" + e.path().string() + "'");
        EXPECT_EQ(r.code, 0) << e.path();
        ++n;
    }
    EXPECT_GT(n, 10);
}

TEST(Cli, ConvertRoundTripsThroughPipesExactly) {
    if (!fs::exists(kData))
        GTEST_SKIP() << "../shared/data is absent";
    fs::path tmp = fs::temp_directory_path() / ("mebake-cli-" + std::to_string(::getpid()));
    fs::create_directories(tmp);
    std::string a = (tmp / "a.ply").string(), b = (tmp / "b.ply").string();
    // binary LE -> ascii (pipe) -> big-endian (pipe) -> binary LE file
    auto r =
        Capture(kBin + " convert " + Scan("horse.ply") + " " + a + " && " + kBin + " convert " + a +
                " - --ascii | " + kBin + " convert - - --format ply --big-endian | " + kBin +
                " convert - " + b + " --format ply");
    ASSERT_EQ(r.code, 0);
    std::ifstream fa(a, std::ios::binary), fb(b, std::ios::binary);
    std::string sa((std::istreambuf_iterator<char>(fa)), {}),
        sb((std::istreambuf_iterator<char>(fb)), {});
    EXPECT_FALSE(sa.empty());
    EXPECT_EQ(sa, sb);
    fs::remove_all(tmp);
}

TEST(Cli, BadInputAndUsageGiveClearErrorsAndExitCodes) {
    fs::path tmp = fs::temp_directory_path() / ("mebake-cli-bad-" + std::to_string(::getpid()));
    fs::create_directories(tmp);
    std::string bad = (tmp / "bad.ply").string();
    {
        std::ofstream f(bad);
        f << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
             "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n";
    }
    auto r = Capture(kBin + " info " + bad + " 2>&1");
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.out.find(bad), std::string::npos) << r.out;
    r = Capture(kBin + " info " + (tmp / "missing.ply").string() + " 2>&1");
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.out.find("missing.ply"), std::string::npos) << r.out;
    EXPECT_EQ(Capture(kBin + " info 2>&1").code, 2);
    EXPECT_EQ(Capture(kBin + " frobnicate 2>&1").code, 2);
    EXPECT_EQ(
        Capture(kBin + " ingest " + bad + " -o " + (tmp / "x").string() + " --memory banana 2>&1")
            .code,
        2);
    // An existing output is not overwritten without --force, and stays intact.
    std::string keep = (tmp / "keep.ply").string();
    {
        std::ofstream f(keep);
        f << "precious";
    }
    EXPECT_EQ(Capture(kBin + " convert " + bad + " " + keep + " 2>&1").code, 2);
    std::ifstream f(keep);
    std::string s((std::istreambuf_iterator<char>(f)), {});
    EXPECT_EQ(s, "precious");
    fs::remove_all(tmp);
}

TEST(Cli, EveryHelpShowsAnExampleThatParses) {
    const auto top = Capture(kBin + " --help");
    EXPECT_EQ(top.code, 0);
    EXPECT_NE(top.out.find("Examples:\n  mebake bake"), std::string::npos) << top.out;
    for (const char* cmd : {"info", "convert", "ingest", "solve", "reference", "compare", "export",
                            "render", "view", "bake"}) {
        const auto r = Capture(kBin + " " + cmd + " --help");
        EXPECT_EQ(r.code, 0) << cmd;
        const size_t at = r.out.find("Example:\n  mebake " + std::string(cmd) + " ");
        ASSERT_NE(at, std::string::npos) << cmd << ":\n" << r.out;
        // The example's options exist: run in an empty directory, it fails on the missing
        // files (a runtime error), never on its options (CLI11's "Run with --help").
        std::string line = r.out.substr(at + 11);
        line = line.substr(0, line.find('\n'));
        line = line.substr(0, line.find("  ("));  // a trailing remark in parentheses
        const fs::path tmp = fs::temp_directory_path() /
                             ("mebake-cli-example-" + std::to_string(::getpid()) + "-" + cmd);
        fs::create_directories(tmp);
        const auto run = Capture("cd '" + tmp.string() + "' && '" + kBin + "'" + line.substr(6) +
                                 " < /dev/null 2>&1");
        EXPECT_EQ(run.out.find("Run with --help"), std::string::npos) << line << ": " << run.out;
        EXPECT_NE(run.code, 2) << line << ": " << run.out;
        fs::remove_all(tmp);
    }
}

TEST(Cli, BakeSampleEndToEnd) {
    fs::path tmp = fs::temp_directory_path() / ("mebake-cli-bake-" + std::to_string(::getpid()));
    std::string sample = std::string(MEBAKE_SOURCE_DIR) + "/data/samples/terrain.ply";
    auto r =
        Capture(kBin + " -q bake " + sample + " -o " + tmp.string() + " --lightmap-resolution 256");
    ASSERT_EQ(r.code, 0);
    for (const char* f :
         {"lightmap.exr", "lightmap.png", "baked.glb", "vertex_colors.ply", "render.png"})
        EXPECT_TRUE(fs::exists(tmp / f)) << f;
    // The vertex-coloured PLY keeps the input's vertex count.
    auto j = nlohmann::json::parse(
        Capture(kBin + " info --json " + (tmp / "vertex_colors.ply").string()).out);
    EXPECT_EQ(j["vertices"].get<uint64_t>(), 2601u);
    EXPECT_TRUE(j["properties"]["colors"].get<bool>());
    // The commands that read a bake directory also take bake's output directory.
    EXPECT_EQ(Capture(kBin + " -q render " + tmp.string() + " --size 64x48 -o " +
                      (tmp / "small.png").string())
                  .code,
              0);
    EXPECT_TRUE(fs::exists(tmp / "small.png"));
    const auto stats = Capture(kBin + " -q export " + tmp.string() + " --stats -");
    EXPECT_EQ(stats.code, 0);
    EXPECT_NO_THROW(nlohmann::json::parse(stats.out)) << stats.out;
    EXPECT_EQ(Capture(kBin + " info " + tmp.string() + " > /dev/null").code, 0);
    fs::remove_all(tmp);
}

}  // namespace
