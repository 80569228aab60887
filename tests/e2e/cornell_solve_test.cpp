// `mebake solve` on a real scene as a user runs it: the Cornell box of the shared data
// (OBJ/MTL, its lamp lit as an exact polygon light) is ingested and solved with
// --threads 1 and --threads 2; both must succeed and write identical solution bytes.
// Skipped when the shared data is absent.
#include "run.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <unistd.h>

namespace mebake {
namespace {

namespace fs = std::filesystem;

using e2e::Mebake;

std::string Slurp(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

TEST(CornellSolveE2E, SolvesAndIsBitIdenticalForOneAndTwoThreads) {
    const std::string obj =
        std::string(MEBAKE_SHARED_DATA) + "/scenes/cornell-mcguire/CornellBox-Original.obj";
    if (!fs::exists(obj))
        GTEST_SKIP() << obj << " not found (shared data absent)";
    const std::string dir =
        (fs::temp_directory_path() / ("mebake-e2e-cornell-" + std::to_string(::getpid()))).string();
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string bake = dir + "/c.mebake";
    ASSERT_EQ(Mebake("-q ingest '" + obj + "' -o '" + bake + "'"), 0) << "ingest failed";
    std::string solution[2];
    for (int threads = 1; threads <= 2; ++threads) {
        ASSERT_EQ(
            Mebake("-q solve '" + bake + "' --max-bounces 2 --threads " + std::to_string(threads)),
            0)
            << "solve --threads " << threads << " failed";
        solution[threads - 1] = Slurp(bake + "/solve/solution.bin");
        ASSERT_GT(solution[threads - 1].size(), 0u) << "no solution written";
    }
    EXPECT_EQ(solution[0].size(), solution[1].size());
    EXPECT_TRUE(solution[0] == solution[1]) << "--threads 1 and 2 wrote different solutions";
    fs::remove_all(dir);
}

}  // namespace
}  // namespace mebake
