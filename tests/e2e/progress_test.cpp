// `--progress json`: one JSON object per line on stderr for every long stage of a bake,
// counts that only grow, a final object per stage; and progress never changes a result byte.
#include "run.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using namespace mebake::e2e;

namespace {

std::string ReadFile(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

fs::path TempDir(const std::string& name) {
    fs::path d = fs::temp_directory_path() / ("mebake_progress_" + name);
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

}  // namespace

TEST(ProgressJson, EveryStageOfABakeReportsAndFinishes) {
    const fs::path tmp = TempDir("json");
    const std::string sample = std::string(MEBAKE_SOURCE_DIR) + "/data/samples/rock.ply";
    const std::string log = (tmp / "stderr.txt").string();
    ASSERT_EQ(Mebake("bake '" + sample + "' -o '" + (tmp / "out").string() +
                     "' --lightmap-resolution 256 --progress json 2> '" + log + "'"),
              0)
        << ReadFile(log);
    std::istringstream lines(ReadFile(log));
    std::string line;
    std::map<std::string, uint64_t> last_done;
    std::set<std::string> finished, with_eta;
    int objects = 0;
    while (std::getline(lines, line)) {
        if (line.empty() || line[0] != '{')
            continue;                                          // log lines
        const nlohmann::json j = nlohmann::json::parse(line);  // throws on a malformed line
        ++objects;
        const std::string stage = j.at("stage");
        const uint64_t done = j.at("done");
        EXPECT_GE(done, last_done[stage]) << line;  // a new stage of the same name starts at 0
        last_done[stage] = j.at("final").get<bool>() ? 0 : done;
        EXPECT_GE(j.at("elapsed").get<double>(), 0) << line;
        if (!j.at("fraction").is_null()) {
            EXPECT_GE(j["fraction"].get<double>(), 0) << line;
            EXPECT_LE(j["fraction"].get<double>(), 1) << line;
        }
        if (!j.at("eta").is_null()) {
            EXPECT_GE(j["eta"].get<double>(), 0) << line;
            with_eta.insert(stage);
        }
        if (j.at("final").get<bool>()) {
            finished.insert(stage);
            if (!j["fraction"].is_null()) {
                EXPECT_EQ(j["fraction"].get<double>(), 1) << line;
            }
        }
    }
    EXPECT_GT(objects, 10);
    for (const char* stage :
         {"spill", "bricks", "orient", "charts", "proxy", "direct", "solve", "export", "render"}) {
        EXPECT_TRUE(finished.count(stage)) << stage << " has no final progress object";
        EXPECT_TRUE(with_eta.count(stage)) << stage << " never had an ETA";
    }
}

// The same bake with and without progress: identical solution and light map.
TEST(ProgressJson, ResultsDoNotDependOnIt) {
    const fs::path tmp = TempDir("bytes");
    const std::string sample = std::string(MEBAKE_SOURCE_DIR) + "/data/samples/rock.ply";
    for (const char* mode : {"off", "json"}) {
        ASSERT_EQ(Mebake("ingest '" + sample + "' -o '" + (tmp / mode).string() +
                         "' --lightmap-resolution 256 --progress " + mode + " 2>/dev/null"),
                  0);
        ASSERT_EQ(Mebake("solve '" + (tmp / mode).string() + "' --progress " + mode +
                         " --max-bounces 2 2>/dev/null"),
                  0);
    }
    const std::string a = ReadFile(tmp / "off" / "solve" / "solution.bin");
    const std::string b = ReadFile(tmp / "json" / "solve" / "solution.bin");
    ASSERT_FALSE(a.empty());
    EXPECT_TRUE(a == b) << "solution.bin differs with --progress json";
}

TEST(ProgressJson, BadModeIsAUsageError) {
    EXPECT_EQ(Mebake("--progress sometimes info x.ply 2>/dev/null"), 2);
}
