// The pipeline of the README: `mkscan | mebake bake - -o - | mebake info -`. A generated
// scan streams in through stdin, is ingested, solved and exported, and the vertex-coloured
// PLY streams out to the next tool, which must read every vertex and face of the input
// with colours. Peak memory of the bake (measured by /usr/bin/time, as the benchmarks do)
// must stay under the --memory budget.
#include "run.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <unistd.h>

namespace mebake {
namespace {

namespace fs = std::filesystem;

std::string Slurp(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// The first capture of `re` in `text` as a number, -1 when absent.
long long Find(const std::string& text, const std::string& re) {
    std::smatch m;
    return std::regex_search(text, m, std::regex(re)) ? std::stoll(m[1].str()) : -1;
}

TEST(PipeBake, GeneratorToBakeToInfo) {
    if (!fs::exists("/usr/bin/time"))
        GTEST_SKIP() << "/usr/bin/time is absent (Debian package `time`)";
    const fs::path dir = fs::temp_directory_path() / ("mebake-pipe-" + std::to_string(getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    constexpr long long kBudgetMiB = 384;
    const std::string cmd =
        "set -o pipefail; cd '" + dir.string() + "' && '" + MEBAKE_MKSCAN +
        "' -n 60000 --seed 3 2> gen.txt | /usr/bin/time -f 'peak_kib=%M' -o time.txt '" +
        MEBAKE_BINARY + "' -q bake - -o - --memory " + std::to_string(kBudgetMiB) +
        "M 2> bake.txt | '" + MEBAKE_BINARY + "' info - > info.txt 2>&1";
    ASSERT_EQ(e2e::Shell("bash -c \"" + cmd + "\""), 0)
        << "pipeline failed:\n"
        << Slurp(dir / "bake.txt") << Slurp(dir / "info.txt");

    const std::string gen = Slurp(dir / "gen.txt"), info = Slurp(dir / "info.txt");
    const long long tris = Find(gen, R"(: (\d+) triangles)");
    const long long verts = Find(gen, R"(, (\d+) vertices)");
    ASSERT_GT(tris, 0) << gen;
    EXPECT_EQ(Find(info, R"(vertices\s+(\d+))"), verts) << info;
    EXPECT_EQ(Find(info, R"(faces\s+(\d+))"), tris) << info;
    EXPECT_NE(info.find("colors yes"), std::string::npos) << info;
    const long long peak_kib = Find(Slurp(dir / "time.txt"), R"(peak_kib=(\d+))");
    ASSERT_GT(peak_kib, 0);
    EXPECT_LT(peak_kib, kBudgetMiB * 1024) << "bake peak RSS over the --memory budget";
    fs::remove_all(dir);
}

}  // namespace
}  // namespace mebake
