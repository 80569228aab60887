// Issue 13's opt-ins for fewer, larger charts through the real binary: `ingest
// --merge-horizon-cells` (the merge's turn bound on cells of 8 light-map texels;
// stream/chart_builder.h) is recorded in the manifest (a bake's resume compares it); the scene file's "solver": {"emitter_texels": N} (Solver::EmitterTop) is
// checked (a bad value is an input error naming the file and the key), reaches the solver
// (a chart larger than 32 x 32 texels gets finer emitter samples: other link rays) and
// writes the same solution bytes for --threads 1 and 2.
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
using mebake::e2e::ReadFile;

const std::string kBin = MEBAKE_BINARY;
const std::string kRock = std::string(MEBAKE_SOURCE_DIR) + "/data/samples/rock.ply";

std::string OptionOf(const std::string& bake, const std::string& key) {
    const auto m = nlohmann::json::parse(ReadFile(bake + "/manifest.json"));
    return m.at("options").value(key, std::string("(none)"));
}

TEST(MergeSettingsE2e, HorizonCellMergeIsRecorded) {
    const fs::path tmp = fs::temp_directory_path() / ("mebake-mergeopt-" + std::to_string(::getpid()));
    fs::create_directories(tmp);
    const std::string bake = (tmp / "rock.mebake").string();
    auto r = Capture(kBin + " -q ingest " + kRock + " -o " + bake + " --merge-horizon-cells 2>&1");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_EQ(OptionOf(bake, "merge_horizon_cells"), "1");
    r = Capture(kBin + " -q ingest " + kRock + " -o " + bake + " --force 2>&1");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_EQ(OptionOf(bake, "merge_horizon_cells"), "0");
    fs::remove_all(tmp);
}

TEST(MergeSettingsE2e, EmitterTexelsIsCheckedAndReachesTheSolver) {
    const fs::path tmp = fs::temp_directory_path() / ("mebake-emtex-" + std::to_string(::getpid()));
    fs::create_directories(tmp);
    const std::string bake = (tmp / "rock.mebake").string();
    // At the default light-map resolution the rock's charts are larger than 32 x 32 texels.
    ASSERT_EQ(Capture(kBin + " -q ingest " + kRock + " -o " + bake + " 2>&1").code, 0);
    const auto m = nlohmann::json::parse(ReadFile(bake + "/manifest.json"));
    uint32_t largest = 0;
    for (const auto& c : m.at("charts"))
        largest = std::max(largest, c.at("resolution").get<uint32_t>());
    ASSERT_GT(largest, 32u);

    const fs::path bad = tmp / "bad.json", fine = tmp / "fine.json", plain = tmp / "plain.json";
    std::ofstream(bad) << R"({"default_rig": true, "solver": {"emitter_texels": 3}})";
    std::ofstream(fine) << R"({"default_rig": true, "solver": {"emitter_texels": 1}})";
    std::ofstream(plain) << R"({"default_rig": true})";
    auto r = Capture(kBin + " solve " + bake + " --scene " + bad.string() + " 2>&1");
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find(bad.string()), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("emitter_texels"), std::string::npos) << r.out;

    auto solve = [&](const fs::path& scene, int threads, nlohmann::json* stats) {
        const fs::path sp = tmp / "stats.json";
        const auto run = Capture(kBin + " -q solve " + bake + " -f --max-bounces 2 --scene " +
                                 scene.string() + " --threads " + std::to_string(threads) +
                                 " --stats " + sp.string() + " 2>&1");
        EXPECT_EQ(run.code, 0) << run.out;
        *stats = nlohmann::json::parse(ReadFile(sp));
        return ReadFile(bake + "/solve/solution.bin");
    };
    nlohmann::json s_plain, s_fine1, s_fine2;
    solve(plain, 2, &s_plain);
    const std::string fine1 = solve(fine, 1, &s_fine1);
    const std::string fine2 = solve(fine, 2, &s_fine2);
    EXPECT_FALSE(fine1.empty());
    EXPECT_EQ(fine1, fine2) << "--threads 1 and 2 differ with emitter_texels";
    EXPECT_NE(s_plain["rays_by_kind"]["link"], s_fine1["rays_by_kind"]["link"]);
    fs::remove_all(tmp);
}

}  // namespace
