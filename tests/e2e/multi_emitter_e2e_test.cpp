// `--multi-emitter` through the real binary: a bad value in the scene file is an input
// error naming the file, a bad command-line value a usage error, and `simplify` on the
// sample rock with three polygon lights writes the same solution bytes for --threads 1
// and 2 and the same leaves as a rerun; --multi-emitter-debug draws a picture per chart
// (one panel per light and one for the refinement) without changing the solution.
#include "io/png_writer.h"
#include "run.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using mebake::e2e::Capture;

const std::string kBin = MEBAKE_BINARY;

std::string Slurp(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(f)), {});
}

// Three 1 x 1 lights around the rock (radius ~1), facing it, and the given solver block.
std::string Scene(const std::string& solver) {
    return R"({"lights": [
 {"type": "polygon", "vertices": [[-0.5, 3, -0.5], [0.5, 3, -0.5], [0.5, 3, 0.5], [-0.5, 3, 0.5]],
  "radiance": [4, 4, 4]},
 {"type": "polygon", "vertices": [[3, -0.5, 0.5], [3, 0.5, 0.5], [3, 0.5, -0.5], [3, -0.5, -0.5]],
  "radiance": [2, 2, 2]},
 {"type": "polygon", "vertices": [[-0.5, 0.5, 3], [0.5, 0.5, 3], [0.5, -0.5, 3], [-0.5, -0.5, 3]],
  "radiance": [1, 1, 1]}],
 "sky": {"type": "none"}, "solver": )" +
           solver + "}";
}

TEST(MultiEmitterE2e, BadValuesAreClearErrorsAndSimplifyIsDeterministic) {
    const fs::path tmp = fs::temp_directory_path() / ("mebake-multi-" + std::to_string(::getpid()));
    fs::create_directories(tmp);
    const std::string rock = std::string(MEBAKE_SOURCE_DIR) + "/data/samples/rock.ply";
    const std::string bake = (tmp / "rock.mebake").string();
    ASSERT_EQ(
        Capture(kBin + " -q ingest " + rock + " -o " + bake + " --lightmap-resolution 256 2>&1")
            .code,
        0);
    const fs::path bad = tmp / "bad.json", good = tmp / "good.json";
    std::ofstream(bad) << Scene(R"({"multi_emitter": "sometimes"})");
    std::ofstream(good) << Scene(R"({"max_bounces": 0, "multi_emitter": "simplify"})");
    auto r = Capture(kBin + " solve " + bake + " --scene " + bad.string() + " 2>&1");
    EXPECT_EQ(r.code, 1) << r.out;
    EXPECT_NE(r.out.find(bad.string()), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("multi_emitter"), std::string::npos) << r.out;
    r = Capture(kBin + " solve " + bake + " --multi-emitter sometimes 2>&1");
    EXPECT_EQ(r.code, 2) << r.out;
    std::string solution[2];
    for (int threads : {1, 2}) {
        const std::string debug =
            threads == 2 ? " --multi-emitter-debug " + (tmp / "debug").string() : "";
        r = Capture(kBin + " -q solve " + bake + " -f --scene " + good.string() + " --threads " +
                    std::to_string(threads) + " --stats " + (tmp / "stats.json").string() + debug +
                    " 2>&1");
        ASSERT_EQ(r.code, 0) << r.out;
        solution[threads - 1] = Slurp(fs::path(bake) / "solve" / "solution.bin");
        // The lights face the rock: the direct pass traced classification rays.
        const auto stats = nlohmann::json::parse(Slurp(tmp / "stats.json"));
        EXPECT_GT(stats["rays_by_kind"]["classify"].get<uint64_t>(), 0u);
    }
    EXPECT_FALSE(solution[0].empty());
    EXPECT_EQ(solution[0], solution[1]) << "--threads 1 and 2 differ under simplify";
    // Four panels of 256 x 256 with 4-pixel gaps; some chart has a lit region (yellow).
    int pictures = 0;
    bool lit = false;
    for (const auto& e : fs::directory_iterator(tmp / "debug")) {
        const std::string bytes = Slurp(e.path());
        const auto png = mebake::io::DecodePng(
            std::span(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
        EXPECT_EQ(png.width, 4 * 256 + 3 * 4);
        EXPECT_EQ(png.height, 256);
        for (size_t k = 0; k + 2 < png.pixels.size(); k += size_t(png.channels))
            lit |= png.pixels[k] == 250 && png.pixels[k + 1] == 215 && png.pixels[k + 2] == 80;
        ++pictures;
    }
    EXPECT_GT(pictures, 0);
    EXPECT_TRUE(lit);
    fs::remove_all(tmp);
}

}  // namespace
