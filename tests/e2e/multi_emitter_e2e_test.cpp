// `--multi-emitter` through the real binary: a bad value in the scene file is an input
// error naming the file, a bad command-line value a usage error, and `simplify` on the
// sample rock with three polygon lights writes the same solution bytes for --threads 1
// and 2 and the same leaves as a rerun; --multi-emitter-debug draws a picture per chart
// (one panel per light and one for the refinement) without changing the solution.
#include "io/png_writer.h"
#include "run.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
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

// Veach's plates (../shared/data/scenes/veach-mis-mitsuba): the five emitting spheres of the
// Mitsuba file become octagons of the same area facing the plates (as
// bench/multi_emitter_scenes.py --veach makes them), radiances 700x apart. Both modes solve
// the direct light alone; at the points of a reference the simplified solution is within
// the tolerance of the full one in L2 (relative to full's mean), with fewer leaves and
// fewer direct-light rays.
namespace {

using Vec = std::array<double, 3>;

Vec Unit(Vec v) {
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return {v[0] / n, v[1] / n, v[2] / n};
}

Vec Cross(const Vec& a, const Vec& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

nlohmann::json Octagon(const Vec& centre, const Vec& towards, double radius, const Vec& radiance) {
    const Vec front = Unit({towards[0] - centre[0], towards[1] - centre[1], towards[2] - centre[2]});
    const Vec up = std::abs(front[1]) < 0.9 ? Vec{0, 1, 0} : Vec{1, 0, 0};
    const Vec t = Unit(Cross(up, front)), b = Cross(front, t);
    const double r = radius * std::sqrt(M_PI / (2 * std::sqrt(2.0)));  // the disc's area
    nlohmann::json verts = nlohmann::json::array();
    for (int k = 0; k < 8; ++k) {
        const double a = 2 * M_PI * k / 8;
        verts.push_back({centre[0] + r * (std::cos(a) * t[0] + std::sin(a) * b[0]),
                         centre[1] + r * (std::cos(a) * t[1] + std::sin(a) * b[1]),
                         centre[2] + r * (std::cos(a) * t[2] + std::sin(a) * b[2])});
    }
    return {{"type", "polygon"}, {"vertices", verts}, {"radiance", radiance}};
}

double Luminance(const nlohmann::json& b) {
    return 0.2126 * b[0].get<double>() + 0.7152 * b[1].get<double>() + 0.0722 * b[2].get<double>();
}

}  // namespace

TEST(MultiEmitterE2e, VeachPlatesSimplifyWithinToleranceOfFullWithFewerLeaves) {
    const fs::path dir = fs::path(MEBAKE_SHARED_DATA) / "scenes/veach-mis-mitsuba";
    if (!fs::exists(dir / "veach_mis.xml"))
        GTEST_SKIP() << "no " << (dir / "veach_mis.xml") << " (../shared/data is absent)";
    const std::string xml = Slurp(dir / "veach_mis.xml");
    nlohmann::json lights = nlohmann::json::array();
    const std::regex shape(R"re(<shape type="sphere">([\s\S]*?)</shape>)re");
    const std::regex centre(R"re(name="center" x="([-\d.]+)" y="([-\d.]+)" z="([-\d.]+)")re");
    const std::regex radius(R"re(name="radius" value="([-\d.]+)")re");
    const std::regex radiance(R"re(<emitter[\s\S]*?name="radiance" value="([^"]+)")re");
    for (auto it = std::sregex_iterator(xml.begin(), xml.end(), shape); it != std::sregex_iterator();
         ++it) {
        const std::string body = (*it)[1];
        std::smatch c, r, e;
        if (!std::regex_search(body, c, centre) || !std::regex_search(body, r, radius) ||
            !std::regex_search(body, e, radiance))
            continue;
        Vec rad{};
        std::istringstream values(std::regex_replace(e[1].str(), std::regex(","), " "));
        values >> rad[0] >> rad[1] >> rad[2];
        lights.push_back(Octagon({std::stod(c[1]), std::stod(c[2]), std::stod(c[3])}, {0, -2, 2.5},
                                 std::stod(r[1]), rad));
    }
    ASSERT_EQ(lights.size(), 5u) << "Veach's file has five emitting spheres";

    const fs::path tmp = fs::temp_directory_path() / ("mebake-veach-" + std::to_string(::getpid()));
    fs::remove_all(tmp);
    fs::create_directories(tmp);
    const fs::path meshes = dir / "meshes/veach";
    std::string inputs;
    for (const char* m : {"plate1", "plate2", "plate3", "plate4", "floor"})
        inputs += " " + (meshes / (std::string(m) + ".obj")).string();
    const std::string base = (tmp / "veach.mebake").string();
    ASSERT_EQ(Capture(kBin + " -q ingest" + inputs + " -o " + base + " 2>&1").code, 0);
    const std::string scene = (tmp / "veach5.json").string();
    const double tolerance = 0.02;
    std::ofstream(scene) << nlohmann::json{{"materials", {{{"albedo", 0.4}}}},
                                           {"lights", lights},
                                           {"sky", {{"type", "none"}}},
                                           {"default_rig", false},
                                           {"solver", {{"max_bounces", 0}, {"tolerance", tolerance}}}}
                                .dump();

    std::map<std::string, nlohmann::json> stats, points;
    for (const std::string mode : {"full", "simplify"}) {
        const std::string bake = (tmp / (mode + ".mebake")).string();
        fs::copy(base, bake, fs::copy_options::recursive);
        const std::string st = (tmp / (mode + ".json")).string();
        ASSERT_EQ(Capture(kBin + " -q solve " + bake + " --scene " + scene + " --multi-emitter " +
                          mode + " --stats " + st + " 2>&1")
                      .code,
                  0);
        stats[mode] = nlohmann::json::parse(Slurp(st));
        if (mode == "full") {  // the reference only places the points (its values are not used)
            ASSERT_EQ(Capture(kBin + " -q reference " + bake + " --points 400 --time-limit 5 -o " +
                              (tmp / "ref.json").string() + " 2>&1")
                          .code,
                      0);
        }
    }
    for (const std::string mode : {"full", "simplify"}) {
        const auto r = Capture(kBin + " -q compare " + (tmp / (mode + ".mebake")).string() + " " +
                               (tmp / "ref.json").string() + " --points 2>/dev/null");
        ASSERT_EQ(r.code, 0);
        points[mode] = nlohmann::json::parse(r.out)["points"];
    }
    ASSERT_EQ(points["full"].size(), points["simplify"].size());
    ASSERT_GT(points["full"].size(), 300u);
    double mean = 0, diff2 = 0;
    for (size_t i = 0; i < points["full"].size(); ++i) {
        const double f = Luminance(points["full"][i]["bake_B"]);
        const double s = Luminance(points["simplify"][i]["bake_B"]);
        mean += f;
        diff2 += (s - f) * (s - f);
    }
    const double n = double(points["full"].size());
    const double l2 = std::sqrt(diff2 / n) / (mean / n);
    std::printf("Veach's plates: L2(simplify - full) / mean %.5f; leaves %llu -> %llu\n", l2,
                stats["full"]["leaves"].get<unsigned long long>(),
                stats["simplify"]["leaves"].get<unsigned long long>());
    EXPECT_LT(l2, tolerance);
    EXPECT_LT(stats["simplify"]["leaves"].get<uint64_t>(), stats["full"]["leaves"].get<uint64_t>());
    auto direct = [](const nlohmann::json& s) {
        const auto& k = s["rays_by_kind"];
        return k.value("classify", uint64_t(0)) + k.value("penumbra", uint64_t(0));
    };
    EXPECT_LT(direct(stats["simplify"]), direct(stats["full"]));
    fs::remove_all(tmp);
}
