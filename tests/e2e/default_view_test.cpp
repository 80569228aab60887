// The default render shows the bake: the object fills the frame, and the default key
// light casts shadows the camera sees. Measured on the image (the default view, a black
// background so that object pixels are the lit ones):
//   fill    the object's extent in the frame's height or width (>= 50 %);
//   shadow  the share of object pixels darker than 35 % of the bright ones (90th
//           percentile of luminance): with key : sky about 3 : 1, a pixel the key does not
//           reach is darker than that (>= 15 %; a coarse measure that shading and
//           albedo also move: the old default view of the sample had 26 %).
//   side    the mean luminance of the object's pixels right of its middle column over
//           those left of it: the key stands on the camera's right (> 1).
// The sample always; every scan in ../shared/data/scans when present (small images, a
// coarse light map, order 1, two batches, to keep the runtime modest), horse.ply too: it
// is wound inwards, and ingest turns it outwards (stream/orient.h). The scans' up axis is
// detected at ingest (stream/up_axis.h): the z-up statue and bust (lucy, nefertiti) must
// stand up in the picture, i.e. be taller than wide (lying on their side they are wider).
#include "io/exr_writer.h"
#include "run.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using namespace mebake;
using namespace mebake::e2e;

namespace {

struct ViewStats {
    double fill = 0;          // max(object rows / height, object columns / width)
    double shadow = 0;        // share of object pixels in the key light's shadow
    double side = 0;          // mean luminance right of the object's middle over left of it
    double aspect = 0;        // object rows / object columns
    std::vector<double> lum;  // per pixel, 0 for the background
    int width = 0, height = 0;
};

ViewStats Measure(const std::string& exr) {
    const io::ExrImage img = io::ReadExr(exr);
    ViewStats s;
    s.width = img.width;
    s.height = img.height;
    const int r = img.Channel("R"), g = img.Channel("G"), b = img.Channel("B");
    EXPECT_GE(r, 0);
    int x0 = img.width, x1 = -1, y0 = img.height, y1 = -1;
    std::vector<double> object;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const double l =
                0.2126 * img.At(x, y, r) + 0.7152 * img.At(x, y, g) + 0.0722 * img.At(x, y, b);
            s.lum.push_back(l);
            if (l <= 0)
                continue;
            object.push_back(l);
            x0 = std::min(x0, x);
            x1 = std::max(x1, x);
            y0 = std::min(y0, y);
            y1 = std::max(y1, y);
        }
    if (object.empty())
        return s;
    s.fill = std::max(double(x1 - x0 + 1) / img.width, double(y1 - y0 + 1) / img.height);
    s.aspect = double(y1 - y0 + 1) / double(x1 - x0 + 1);
    double sum[2] = {0, 0}, count[2] = {0, 0};
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            if (const double l = s.lum[size_t(y) * size_t(img.width) + size_t(x)]; l > 0) {
                const int half = 2 * x > x0 + x1 ? 1 : 0;
                sum[half] += l;
                count[half] += 1;
            }
    if (count[0] > 0 && count[1] > 0 && sum[0] > 0)
        s.side = (sum[1] / count[1]) / (sum[0] / count[0]);
    std::vector<double> sorted = object;
    std::sort(sorted.begin(), sorted.end());
    const double bright = sorted[sorted.size() * 9 / 10];
    const auto dark =
        std::count_if(object.begin(), object.end(), [&](double l) { return l < 0.35 * bright; });
    s.shadow = double(dark) / double(object.size());
    return s;
}

class DefaultView : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("mebake-defview-" + std::to_string(getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    // Ingest, solve and render the default view of `mesh`; returns the image's statistics.
    ViewStats BakeAndMeasure(const std::string& mesh, const std::string& name,
                             const std::string& ingest_flags = "") {
        const std::string bake = (dir_ / (name + ".mebake")).string();
        const std::string exr = (dir_ / (name + ".exr")).string();
        EXPECT_EQ(Mebake("-q ingest '" + mesh + "' -o '" + bake + "' --lightmap-resolution 256 " +
                         ingest_flags),
                  0);
        EXPECT_EQ(Mebake("-q solve '" + bake + "' --order 1 --max-bounces 2"), 0);
        EXPECT_EQ(Mebake("-q render '" + bake + "' --size 160x120 --background 0,0,0 --float -o '" +
                         exr + "'"),
                  0);
        if (!fs::exists(exr))
            return {};
        return Measure(exr);
    }

    // The up axis the ingest of `name` recorded, as JSON.
    std::string UpOf(const std::string& name) const {
        std::ifstream f(dir_ / (name + ".mebake") / "manifest.json");
        return nlohmann::json::parse(f).at("up").dump();
    }

    fs::path dir_;
};

}  // namespace

TEST_F(DefaultView, SampleFillsTheFrameAndShowsTheKeyShadow) {
    const std::string sample = std::string(MEBAKE_SOURCE_DIR) + "/data/samples/rock.ply";
    const ViewStats s = BakeAndMeasure(sample, "rock");
    std::printf("rock: fill %.2f, shadow %.3f\n", s.fill, s.shadow);
    EXPECT_GE(s.fill, 0.5) << "the object fills too little of the frame";
    EXPECT_LT(s.fill, 1.0) << "the object is cut by the frame";
    EXPECT_GE(s.shadow, 0.15) << "too few object pixels in the key light's shadow";
}

// --ground: the camera still frames the object, and the ground around it receives its
// shadow (ground pixels much darker than the ground's median).
TEST_F(DefaultView, GroundReceivesTheShadow) {
    const std::string sample = std::string(MEBAKE_SOURCE_DIR) + "/data/samples/rock.ply";
    const ViewStats plain = BakeAndMeasure(sample, "plain");
    const ViewStats ground = BakeAndMeasure(sample, "ground", "--ground");
    ASSERT_EQ(plain.lum.size(), ground.lum.size());
    std::vector<double> floor;  // pixels that only the ground render hits
    for (size_t i = 0; i < plain.lum.size(); ++i)
        if (plain.lum[i] <= 0 && ground.lum[i] > 0)
            floor.push_back(ground.lum[i]);
    ASSERT_GT(floor.size(), plain.lum.size() / 10) << "the ground is not in view";
    std::vector<double> sorted = floor;
    std::sort(sorted.begin(), sorted.end());
    const double median = sorted[sorted.size() / 2];
    const auto dark =
        std::count_if(floor.begin(), floor.end(), [&](double l) { return l < 0.5 * median; });
    EXPECT_GE(double(dark) / double(floor.size()), 0.01) << "no shadow on the ground";
}

TEST_F(DefaultView, EverySharedScan) {
    const fs::path scans = fs::path(MEBAKE_SHARED_DATA) / "scans";
    if (!fs::exists(scans))
        GTEST_SKIP() << scans << " is absent (../shared/data not beside the checkout)";
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(scans))
        if (e.path().extension() == ".ply" || e.path().extension() == ".obj")
            files.push_back(e.path());
    std::sort(files.begin(), files.end());
    ASSERT_FALSE(files.empty());
    for (const fs::path& f : files) {
        const ViewStats s = BakeAndMeasure(f.string(), f.stem().string());
        EXPECT_GE(s.fill, 0.5) << f.filename() << ": the object fills too little of the frame";
        EXPECT_GE(s.shadow, 0.15) << f.filename() << ": too few pixels in the key's shadow";
        EXPECT_GT(s.side, 1.0) << f.filename() << ": not lit from the key's side";
        const std::string up = UpOf(f.stem().string());
        std::printf("%-24s fill %.2f, shadow %.3f, side %.2f, aspect %.2f, up %s\n",
                    f.filename().c_str(), s.fill, s.shadow, s.side, s.aspect, up.c_str());
        if (f.stem() == "lucy" || f.stem() == "nefertiti") {
            EXPECT_EQ(up, "[0.0,0.0,1.0]") << f.filename() << ": its z-up not detected";
            EXPECT_GT(s.aspect, 1.0) << f.filename() << ": does not stand up in the picture";
        }
    }
}
