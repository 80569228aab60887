// The sky's opt-in deeper refinement through the real binary (scene file "solver":
// sky_extra_levels, sky_fit_floor; docs/scene-format.md): a bad value is an input error
// naming the file and the key; the settings reach the solver (the sample rock under the
// default rig refines its sky differently with the shallower sky of sessions 1-17: other
// leaves, other sky rays) and the default deeper sky writes the same solution bytes for
// --threads 1 and 2.
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

TEST(SkySettingsE2e, BadValuesAreClearErrorsAndTheOptInIsDeterministic) {
    const fs::path tmp = fs::temp_directory_path() / ("mebake-sky-" + std::to_string(::getpid()));
    fs::create_directories(tmp);
    const std::string bake = (tmp / "rock.mebake").string();
    ASSERT_EQ(mebake::e2e::IngestSampleRock(bake), 0);
    const fs::path bad = tmp / "bad.json", deep = tmp / "deep.json", plain = tmp / "plain.json";
    std::ofstream(bad) << R"({"default_rig": true, "solver": {"sky_extra_levels": 12}})";
    std::ofstream(deep)
        << R"({"default_rig": true, "solver": {"sky_extra_levels": 4, "sky_fit_floor": 4}})";
    std::ofstream(plain)
        << R"({"default_rig": true, "solver": {"sky_extra_levels": 2, "sky_fit_floor": 0}})";
    auto r = Capture(kBin + " solve " + bake + " --scene " + bad.string() + " 2>&1");
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find(bad.string()), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("sky_extra_levels"), std::string::npos) << r.out;

    auto solve = [&](const fs::path& scene, int threads, nlohmann::json* stats) {
        const fs::path sp = tmp / "stats.json";
        const auto run =
            Capture(kBin + " -q solve " + bake + " -f --scene " + scene.string() + " --threads " +
                    std::to_string(threads) + " --stats " + sp.string() + " 2>&1");
        EXPECT_EQ(run.code, 0) << run.out;
        *stats = nlohmann::json::parse(ReadFile(sp));
        return ReadFile(bake + "/solve/solution.bin");
    };
    nlohmann::json s_plain, s_deep1, s_deep2;
    solve(plain, 2, &s_plain);
    const std::string deep1 = solve(deep, 1, &s_deep1);
    const std::string deep2 = solve(deep, 2, &s_deep2);
    EXPECT_FALSE(deep1.empty());
    EXPECT_EQ(deep1, deep2) << "--threads 1 and 2 differ with the deeper sky";
    EXPECT_NE(s_plain["leaves"], s_deep1["leaves"]);
    EXPECT_NE(s_plain["rays_by_kind"]["sky"], s_deep1["rays_by_kind"]["sky"]);
    fs::remove_all(tmp);
}

}  // namespace
