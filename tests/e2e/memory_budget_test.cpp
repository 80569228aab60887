// The one memory budget (core/memory_budget.h) end to end: the solve prints its split in
// the statistics, and Embree's allocations are capped by it: under 256M a visibility mesh
// too large for the cap is traced in pieces instead of exceeding it; at 1G it is whole.
#include "run.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <unistd.h>

namespace mebake::e2e {
namespace {

namespace fs = std::filesystem;

TEST(MemoryBudget, SolveReportsSharesAndCapsEmbree) {
    const fs::path dir =
        fs::temp_directory_path() / ("mebake-budget-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string bake = (dir / "s.mebake").string();
    // 400K triangles: the full mesh is the visibility mesh (~22 MB of Embree scene, over
    // half the 32 MiB cap of --memory 64M).
    ASSERT_EQ(Shell(std::string("'") + MEBAKE_MKSCAN + "' --triangles 400000 | '" + MEBAKE_BINARY +
                    "' -q ingest - -o '" + bake + "' --memory 1G"),
              0);
    // 64M allows Embree 32 MiB: the scene does not fit, so it is traced in pieces
    // (solve/paged_visibility.h) and Embree stays under the cap. Both solves fit constants
    // at a loose tolerance: the visibility and the shares do not depend on the fit, and it
    // takes a third of the default's rays.
    const std::string small_stats = (dir / "small.json").string();
    const std::string fit = " --max-bounces 0 --order 0 --tolerance 0.5";
    const RunResult small = Capture(std::string("'") + MEBAKE_BINARY + "' -q solve '" + bake +
                                    "' --memory 64M" + fit + " --stats '" + small_stats +
                                    "' 2>&1");
    ASSERT_EQ(small.code, 0) << small.out;
    {
        std::ifstream sin(small_stats);
        const auto js = nlohmann::json::parse(sin);
        EXPECT_TRUE(js["visibility"]["paged"].get<bool>());
        EXPECT_LE(js["embree_bytes"].get<int64_t>(), int64_t(32) << 20) << "under the 32 MiB cap";
    }

    const std::string stats = (dir / "stats.json").string();
    ASSERT_EQ(Mebake("-q solve '" + bake + "' --force --memory 1G" + fit + " --stats '" + stats +
                     "'"),
              0);
    std::ifstream in(stats);
    const auto j = nlohmann::json::parse(in);
    EXPECT_FALSE(j["visibility"]["paged"].get<bool>()) << "the full mesh fits at 1G";
    EXPECT_EQ(j["memory"]["budget_bytes"].get<uint64_t>(), uint64_t(1) << 30);
    bool visibility = false;
    for (const auto& s : j["memory"]["shares"])
        if (s["name"] == "solve.visibility") {
            visibility = true;
            EXPECT_EQ(s["bytes"].get<uint64_t>(), uint64_t(64) << 20);
        }
    EXPECT_TRUE(visibility);
    EXPECT_LE(j["embree_bytes"].get<int64_t>(), int64_t(1) << 27) << "under the 128 MiB cap";
    fs::remove_all(dir);
}

}  // namespace
}  // namespace mebake::e2e
