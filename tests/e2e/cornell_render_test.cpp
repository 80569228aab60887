// Renders McGuire's Cornell box (../shared/data/scenes/cornell-mcguire) through the whole
// pipeline (ingest, solve, render) and compares the linear EXR with a stored reference
// image, tests/data/cornell_original.exr. The reference was rendered by mebake itself
// (its accuracy against an independent path tracer is what bench/accuracy measures); this
// test guards against regressions in any stage that would change what a user sees. Regenerate it
// deliberately with MEBAKE_UPDATE_REFERENCE=1 after a change that is meant to alter the image, and
// say why in the commit.
#include "io/exr_writer.h"
#include "run.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace mebake {
namespace {

namespace fs = std::filesystem;

using e2e::Mebake;

double Luminance(const io::ExrImage& im, int x, int y) {
    const int r = im.Channel("R"), g = im.Channel("G"), b = im.Channel("B");
    return 0.2126 * im.At(x, y, r) + 0.7152 * im.At(x, y, g) + 0.0722 * im.At(x, y, b);
}

// Mean of one channel over a pixel rectangle.
double Mean(const io::ExrImage& im, const char* channel, int x0, int y0, int x1, int y1) {
    const int c = im.Channel(channel);
    double s = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
            s += im.At(x, y, c);
    return s / double((x1 - x0) * (y1 - y0));
}

TEST(CornellRender, MatchesTheStoredReference) {
    const std::string obj =
        std::string(MEBAKE_SHARED_DATA) + "/scenes/cornell-mcguire/CornellBox-Original.obj";
    if (!fs::exists(obj))
        GTEST_SKIP() << obj << " is absent (../shared/data not beside the checkout)";
    const fs::path dir = fs::temp_directory_path() / ("mebake-cornell-" + std::to_string(getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string bake = (dir / "cb.mebake").string();
    const std::string image = (dir / "cb.exr").string();
    ASSERT_EQ(Mebake("-q ingest '" + obj + "' -o '" + bake + "' --lightmap-resolution 512"), 0);
    ASSERT_EQ(Mebake("-q solve '" + bake + "'"), 0);
    ASSERT_EQ(Mebake("-q render '" + bake +
                     "' --eye 0 1 3.4 --target 0 1 0 --fov 40 --size 160x120 "
                     "--background 0 0 0 --float -o '" +
                     image + "'"),
              0);
    const std::string ref_path =
        std::string(MEBAKE_SOURCE_DIR) + "/tests/data/cornell_original.exr";
    if (std::getenv("MEBAKE_UPDATE_REFERENCE")) {
        fs::copy_file(image, ref_path, fs::copy_options::overwrite_existing);
        GTEST_SKIP() << "reference rewritten: " << ref_path;
    }
    const io::ExrImage got = io::ReadExr(image);
    const io::ExrImage ref = io::ReadExr(ref_path);
    ASSERT_EQ(got.width, ref.width);
    ASSERT_EQ(got.height, ref.height);
    ASSERT_GE(got.Channel("R"), 0);

    // What a viewer compares: luminance, relative RMS over the image, and the colour
    // bleeding that makes it a Cornell box (red left wall, green right wall).
    double err2 = 0, ref2 = 0, ref_sum = 0;
    int coverage_mismatch = 0;
    for (int y = 0; y < ref.height; ++y)
        for (int x = 0; x < ref.width; ++x) {
            const double a = Luminance(got, x, y), b = Luminance(ref, x, y);
            ASSERT_TRUE(std::isfinite(a) && a >= 0) << "pixel " << x << "," << y << ": " << a;
            err2 += (a - b) * (a - b);
            ref2 += b * b;
            ref_sum += b;
            coverage_mismatch += (a > 0) != (b > 0);
        }
    ASSERT_GT(ref_sum, 0);
    const double rel_rms = std::sqrt(err2 / ref2);
    EXPECT_LT(rel_rms, 0.05) << "relative RMS difference of luminance from the reference";
    EXPECT_LT(coverage_mismatch, ref.width * ref.height / 100) << "pixels hit in one image only";
    const int w = got.width, h = got.height;
    // Left wall (x in [0.1, 0.2] of the width): red dominates; right wall: green.
    EXPECT_GT(Mean(got, "R", w / 10, h / 3, w / 5, h / 2),
              2 * Mean(got, "G", w / 10, h / 3, w / 5, h / 2));
    EXPECT_GT(Mean(got, "G", 4 * w / 5, h / 3, 9 * w / 10, h / 2),
              2 * Mean(got, "R", 4 * w / 5, h / 3, 9 * w / 10, h / 2));
    fs::remove_all(dir);
}

}  // namespace
}  // namespace mebake
