// `mebake view` end to end: the page served for a bake, drawn by headless Chromium
// (software WebGL2 through SwiftShader), must show what `mebake render` computes on the
// CPU for the same camera: the vector-irradiance diffuse display and the seed's glossy
// display, RMS difference of the 8-bit sRGB images under 3 % of the render's mean. The
// sample rock (default rig, a glossy rule for every material) and McGuire's Cornell box
// (its OBJ/MTL emitter, glossy floor and boxes; skipped without ../shared/data).
// Also: `export --web` writes the page, and bad input gets clear errors and a non-zero
// exit (not a bake, not solved, a port in use).
//
// The browser is driven by tests/e2e/view_driver.mjs (node + playwright-core from the
// build's npm install). Skipped, with a message, only when chromium or node is absent;
// playwright-core is part of the build, so its absence fails.
#include "io/png_writer.h"
#include "run.h"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <netinet/in.h>
#include <string>
#include <sys/socket.h>
#include <unistd.h>

namespace mebake {
namespace {

namespace fs = std::filesystem;
using e2e::Capture;
using e2e::Mebake;

const char* kChromium = "/usr/bin/chromium";
constexpr double kTolerance = 0.03;  // RMS difference / mean of the render, 8-bit sRGB

std::string NodeModules() {
    return std::string(MEBAKE_BINARY_DIR) + "/web/node_modules";
}

// Empty when the browser can run; else why not (a skip message).
std::string BrowserMissing() {
    if (!fs::exists(kChromium))
        return std::string(kChromium) +
               " is absent (Debian package chromium; scripts/install-deps.sh)";
    if (e2e::Shell("node --version >/dev/null 2>&1") != 0)
        return "node is absent (Debian package nodejs)";
    return "";
}

struct Compared {
    double rms = 0, mean = 0;  // over all pixels and channels, 8-bit units
    int width = 0, height = 0;
};

Compared Compare(const std::string& a_path, const std::string& b_path) {
    const io::PngImage a = io::ReadPng(a_path), b = io::ReadPng(b_path);
    Compared c;
    c.width = a.width;
    c.height = a.height;
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    if (a.width != b.width || a.height != b.height)
        return c;
    double sq = 0, sum = 0;
    size_t n = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x)
            for (int k = 0; k < 3; ++k) {
                const double u = a.pixels[(size_t(y) * a.width + x) * a.channels + k];
                const double v = b.pixels[(size_t(y) * b.width + x) * b.channels + k];
                sq += (u - v) * (u - v);
                sum += u;
                ++n;
            }
    c.rms = std::sqrt(sq / double(n));
    c.mean = sum / double(n);
    return c;
}

class ViewE2E : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        dir_ = fs::temp_directory_path() / ("mebake-view-" + std::to_string(getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    static void TearDownTestSuite() { fs::remove_all(dir_); }
    static std::string Path(const std::string& name) { return (dir_ / name).string(); }

    // Bakes `input` with `scene` (JSON text) into `name`.mebake; returns the directory.
    static std::string Bake(const std::string& name, const std::string& input,
                            const std::string& scene, const std::string& ingest_args) {
        const std::string bake = Path(name + ".mebake"), scene_file = Path(name + ".json");
        std::ofstream(scene_file) << scene;
        EXPECT_EQ(Mebake("-q ingest '" + input + "' -o '" + bake + "' " + ingest_args), 0);
        EXPECT_EQ(Mebake("-q solve '" + bake + "' --scene '" + scene_file + "'"), 0);
        return bake;
    }

    // Renders `camera` on the CPU and in the browser in diffuse and glossy mode; expects
    // each pair within the tolerance.
    static void ExpectBrowserMatchesRender(const std::string& bake, const std::string& name,
                                           const std::string& eye, const std::string& target,
                                           double fov, bool overlay_shot = false) {
        const std::string size = "320x240";
        const std::string cam = "--eye " + eye + " --target " + target + " --fov " +
                                std::to_string(fov) + " --size " + size;
        const std::string query =
            "eye=" + eye + "&target=" + target + "&fov=" + std::to_string(fov);
        std::string shots;
        for (const char* mode : {"diffuse", "glossy"}) {
            const std::string cpu = Path(name + "-cpu-" + mode + ".png");
            ASSERT_EQ(Mebake("-q render '" + bake + "' " + cam + " -o '" + cpu + "' -f" +
                             (std::string(mode) == "glossy" ? " --glossy" : "")),
                      0);
            shots += " --shot '" + Path(name + "-web-" + mode + ".png") + "=" + query +
                     "&mode=" + mode + "'";
        }
        // The page as a user sees it (panel, chart borders, quadtree leaves): kept for the
        // README with MEBAKE_VIEW_SCREENSHOTS=DIR, not compared.
        if (overlay_shot)
            shots += " --shot '" + Path(name + "-web-overlay.png") + "=ui=1&" + query +
                     "&mode=glossy&borders=1&leaves=1'";
        const auto r = Capture("node '" MEBAKE_SOURCE_DIR "/tests/e2e/view_driver.mjs' "
                               "--node-modules '" +
                               NodeModules() + "' --mebake '" MEBAKE_BINARY "' --dir '" + bake +
                               "' --size " + size + shots);
        ASSERT_EQ(r.code, 0) << "view_driver.mjs failed: " << r.out;
        EXPECT_NE(r.out.find("\"serverExit\":0"), std::string::npos)
            << "mebake view did not stop with exit 0 on SIGINT: " << r.out;
        for (const char* mode : {"diffuse", "glossy"}) {
            const Compared c =
                Compare(Path(name + "-cpu-" + mode + ".png"), Path(name + "-web-" + mode + ".png"));
            std::printf("%s %s: RMS %.2f of mean %.2f (8-bit) = %.2f %%\n", name.c_str(), mode,
                        c.rms, c.mean, 100 * c.rms / c.mean);
            EXPECT_GT(c.mean, 5) << "the render is (nearly) black: nothing to compare";
            EXPECT_LT(c.rms, kTolerance * c.mean) << name << " " << mode;
        }
        // The comparison can fail: the glossy lobe changes the image by more than the
        // tolerance (else a page showing diffuse in glossy mode would pass).
        const Compared lobe =
            Compare(Path(name + "-cpu-diffuse.png"), Path(name + "-cpu-glossy.png"));
        EXPECT_GT(lobe.rms, kTolerance * lobe.mean) << name << ": glossy too close to diffuse";
        if (const char* keep = std::getenv("MEBAKE_VIEW_SCREENSHOTS"))
            for (const char* shot : {"diffuse", "glossy", "overlay"})
                if (fs::exists(Path(name + "-web-" + shot + ".png")))
                    fs::copy_file(Path(name + "-web-" + shot + ".png"),
                                  std::string(keep) + "/" + name + "-web-" + shot + ".png",
                                  fs::copy_options::overwrite_existing);
    }

    static inline fs::path dir_;
};

TEST_F(ViewE2E, RockInTheBrowserMatchesRender) {
    if (const std::string why = BrowserMissing(); !why.empty())
        GTEST_SKIP() << why;
    ASSERT_TRUE(fs::exists(NodeModules() + "/playwright-core"))
        << NodeModules() << "/playwright-core is missing: the build's npm ci did not run";
    const std::string bake = Bake(
        "rock", MEBAKE_SOURCE_DIR "/data/samples/rock.ply",
        R"({"default_rig": true, "materials": [{"glossy_exponent": 20, "glossy_weight": 0.4}]})",
        "--lightmap-resolution 512");
    ExpectBrowserMatchesRender(bake, "rock", "2.2,1.4,2.6", "0,0,0", 40);
}

TEST_F(ViewE2E, CornellBoxInTheBrowserMatchesRender) {
    if (const std::string why = BrowserMissing(); !why.empty())
        GTEST_SKIP() << why;
    const std::string obj =
        std::string(MEBAKE_SHARED_DATA) + "/scenes/cornell-mcguire/CornellBox-Original.obj";
    if (!fs::exists(obj))
        GTEST_SKIP() << obj << " is absent (../shared/data not beside the checkout)";
    const std::string bake =
        Bake("cornell", obj,
             R"({"materials": [{"name": "floor", "glossy_exponent": 30, "glossy_weight": 0.5},
                          {"name": "tallBox", "glossy_exponent": 10, "glossy_weight": 0.3}]})",
             "--lightmap-resolution 512");
    // Off the box's symmetry plane: with eye and target at y = 1 the ceiling edge falls on a
    // row of pixel centres, and a whole row flips between rasterization and ray casting.
    ExpectBrowserMatchesRender(bake, "cornell", "0.13,1.07,3.4", "0,0.95,0", 40, true);
}

TEST_F(ViewE2E, ExportWebWritesThePage) {
    const std::string bake = Bake("small", MEBAKE_SOURCE_DIR "/data/samples/rock.ply",
                                  R"({"default_rig": true})", "--lightmap-resolution 128");
    const std::string out = Path("site");
    ASSERT_EQ(Mebake("-q export '" + bake + "' --web '" + out + "'"), 0);
    for (const char* f : {"index.html", "viewer.js", "shade.frag", "three/three.module.min.js",
                          "three/addons/loaders/GLTFLoader.js", "data/view.json",
                          "data/mesh.000.glb", "data/lightmap.0.half", "data/E.z.0.half"})
        EXPECT_TRUE(fs::exists(out + "/" + f)) << f;
    // The same bytes for any thread count.
    const std::string one = Path("site1");
    ASSERT_EQ(Mebake("-q export '" + bake + "' --web '" + one + "' --threads 1"), 0);
    EXPECT_EQ(e2e::Shell("diff -r '" + out + "' '" + one + "' >/dev/null"), 0)
        << "export --web differs between --threads 1 and all threads";
    // Not over a directory with files in it unless forced.
    EXPECT_NE(Mebake("-q export '" + bake + "' --web '" + out + "' 2>/dev/null"), 0);
    EXPECT_EQ(Mebake("-q export '" + bake + "' --web '" + out + "' --force"), 0);
}

TEST_F(ViewE2E, BadInputGetsClearErrors) {
    // Not a bake directory.
    fs::create_directories(Path("empty"));
    auto r = Capture("'" MEBAKE_BINARY "' view '" + Path("empty") + "' --port 0 2>&1");
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.out.find("not a bake directory"), std::string::npos) << r.out;
    // Ingested but not solved.
    const std::string unsolved = Path("unsolved.mebake");
    ASSERT_EQ(Mebake("-q ingest '" MEBAKE_SOURCE_DIR "/data/samples/rock.ply' -o '" + unsolved +
                     "' --lightmap-resolution 128"),
              0);
    r = Capture("'" MEBAKE_BINARY "' view '" + unsolved + "' --port 0 2>&1");
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.out.find("not solved"), std::string::npos) << r.out;
    // A port another socket listens on.
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    ASSERT_GE(fd, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    ASSERT_EQ(listen(fd, 1), 0);
    socklen_t len = sizeof a;
    ASSERT_EQ(getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len), 0);
    const int port = ntohs(a.sin_port);
    const std::string solved = Bake("solved", MEBAKE_SOURCE_DIR "/data/samples/rock.ply",
                                    R"({"default_rig": true})", "--lightmap-resolution 128");
    r = Capture("'" MEBAKE_BINARY "' view '" + solved + "' --port " + std::to_string(port) +
                " 2>&1");
    close(fd);
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.out.find("Address already in use"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace mebake
