// output/image_compare.h: identical pictures score 0, a known offset scores its known RMS
// and bias, coverage limits the pixels, and bad input is an error naming the file.
#include "output/image_compare.h"

#include "core/error.h"
#include "io/exr_writer.h"
#include "io/png_writer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <unistd.h>

namespace mebake::output {
namespace {

namespace fs = std::filesystem;

ComparedImage Flat(int w, int h, float v) {
    ComparedImage im;
    im.path = "flat";
    im.width = w;
    im.height = h;
    im.rgb.assign(size_t(w) * size_t(h) * 3, v);
    return im;
}

TEST(ImageCompare, IdenticalPicturesScoreZero) {
    ComparedImage a = Flat(8, 4, 0.3f);
    a.rgb[5] = 2.f;
    const ImageDifference d = CompareImages(a, a, ToneMap{});
    EXPECT_EQ(d.pixels, 32u);
    EXPECT_EQ(d.relative_rms, 0);
    EXPECT_EQ(d.relative_max, 0);
    EXPECT_EQ(d.display_rms, 0);
    EXPECT_FALSE(d.masked);
}

TEST(ImageCompare, KnownOffsetGivesItsRms) {
    // Reference 2 everywhere; the image is 2.2 on half the pixels and 2 on the rest:
    // RMS = sqrt(0.5 * 0.2^2) / 2 = 7.07 %, max and p95 = 10 %, bias 0.5 * 0.2 / 2 = 5 %.
    const ComparedImage ref = Flat(10, 10, 2.f);
    ComparedImage im = Flat(10, 10, 2.f);
    for (size_t p = 0; p < 50; ++p)
        for (int c = 0; c < 3; ++c)
            im.rgb[3 * p + size_t(c)] = 2.2f;
    const ImageDifference d = CompareImages(im, ref, ToneMap{});
    EXPECT_NEAR(d.relative_rms, std::sqrt(0.5) * 0.1, 1e-6);
    EXPECT_NEAR(d.relative_max, 0.1, 1e-6);
    EXPECT_NEAR(d.relative_p95, 0.1, 1e-6);
    EXPECT_NEAR(d.relative_bias, 0.05, 1e-6);
    EXPECT_GT(d.display_rms, 0);
    // The other way round: the same RMS, the opposite bias (2 is 0.2 below 2.2 on half).
    const ImageDifference back = CompareImages(ref, im, ToneMap{});
    EXPECT_NEAR(back.relative_bias * back.mean_reference, -0.1, 1e-6);
}

TEST(ImageCompare, CoverageAndNoise) {
    ComparedImage ref = Flat(4, 1, 1.f);
    ref.coverage = {1, 1, 0.5f, 0};  // only the first two pixels count
    ref.se.assign(12, 0.03f);
    ComparedImage im = Flat(4, 1, 1.f);
    for (int c = 0; c < 3; ++c) {
        im.rgb[size_t(c)] = 1.05f;      // counted: 5 % off
        im.rgb[6 + size_t(c)] = 100.f;  // not counted
    }
    const ImageDifference d = CompareImages(im, ref, ToneMap{});
    EXPECT_TRUE(d.masked);
    EXPECT_EQ(d.pixels, 2u);
    EXPECT_NEAR(d.relative_rms, 0.05 / std::sqrt(2.0), 1e-6);
    ASSERT_TRUE(d.noise_rms.has_value());
    EXPECT_NEAR(*d.noise_rms, 0.03, 1e-6);
    EXPECT_NEAR(*d.corrected_rms, std::sqrt(0.05 * 0.05 / 2 - 0.03 * 0.03), 1e-6);
    // The difference picture: red where brighter, white where equal, grey outside.
    const auto rgb = DifferencePicture(im, ref, ToneMap{}, 0.1);
    EXPECT_EQ(rgb[0], 255);
    EXPECT_LT(rgb[1], 255);
    EXPECT_EQ(rgb[3], 255);
    EXPECT_EQ(rgb[4], 255);
    EXPECT_EQ(rgb[9], rgb[10]);
    EXPECT_LT(rgb[9], 255);
}

TEST(ImageCompare, SilhouettePixelsAreTheOutline) {
    // A 3 x 3 object in a 5 x 5 frame: its 8 outer pixels touch the background, the centre
    // does not. 10 % off at one outline pixel and 30 % at the centre.
    ComparedImage ref = Flat(5, 5, 1.f);
    ref.coverage.assign(25, 0.f);
    for (int y = 1; y <= 3; ++y)
        for (int x = 1; x <= 3; ++x)
            ref.coverage[size_t(y * 5 + x)] = 1.f;
    ComparedImage im = Flat(5, 5, 1.f);
    for (int c = 0; c < 3; ++c) {
        im.rgb[3 * 6 + size_t(c)] = 1.1f;   // (1, 1): outline
        im.rgb[3 * 12 + size_t(c)] = 1.3f;  // (2, 2): centre
    }
    const ImageDifference d = CompareImages(im, ref, ToneMap{});
    EXPECT_EQ(d.pixels, 9u);
    EXPECT_EQ(d.silhouette_pixels, 8u);
    ASSERT_TRUE(d.silhouette_rms.has_value());
    EXPECT_NEAR(*d.silhouette_rms, 0.1 / std::sqrt(8.0), 1e-6);
    // Without a coverage channel every pixel counts: no outline to speak of.
    ref.coverage.clear();
    EXPECT_FALSE(CompareImages(im, ref, ToneMap{}).silhouette_rms.has_value());
}

TEST(ImageCompare, ChartBordersSplitTheRms) {
    // Charts 0 | 1 side by side: pixels 1 and 2 touch the border, 0 and 3 do not.
    ComparedImage ref = Flat(4, 1, 1.f);
    ref.chart = {0, 0, 1, 1};
    ComparedImage im = Flat(4, 1, 1.f);
    for (int c = 0; c < 3; ++c)
        im.rgb[3 + size_t(c)] = 1.2f;  // 20 % off at pixel 1
    const ImageDifference d = CompareImages(im, ref, ToneMap{});
    EXPECT_EQ(d.border_pixels, 2u);
    ASSERT_TRUE(d.border_rms.has_value());
    EXPECT_NEAR(*d.border_rms, 0.2 / std::sqrt(2.0), 1e-6);
    EXPECT_EQ(*d.interior_rms, 0);
    // The overlay: a black line on pixel 1 (its right neighbour is another chart).
    const auto rgb = DifferencePicture(im, ref, ToneMap{}, 0.1, nullptr, true);
    EXPECT_EQ(rgb[3] + rgb[4] + rgb[5], 0);
    EXPECT_EQ(rgb[0], 255);
}

TEST(ImageCompare, RuleSplitFindsTheCarriedShare) {
    // Reference 1 on 4 pixels; the rule picture loses 0.2 on pixel 0 and 0.1 on pixel 1.
    // The image carries half of that loss and has its own error of 0.1 on pixels 2 and 3
    // (orthogonal to the loss): slope 0.5, carried 0.5 x rule RMS, and RMS^2 = carried^2 +
    // rest^2 with rest = sqrt(2 x 0.1^2 / 4) = 7.07 %.
    const ComparedImage ref = Flat(4, 1, 1.f);
    ComparedImage rule = Flat(4, 1, 1.f), im = Flat(4, 1, 1.f);
    const float loss[4] = {-0.2f, -0.1f, 0, 0}, own[4] = {0, 0, 0.1f, -0.1f};
    for (size_t p = 0; p < 4; ++p)
        for (int c = 0; c < 3; ++c) {
            rule.rgb[3 * p + size_t(c)] = 1 + loss[p];
            im.rgb[3 * p + size_t(c)] = 1 + 0.5f * loss[p] + own[p];
        }
    const RuleSplit s = SplitByRule(im, ref, rule, ToneMap{});
    const double rule_rms = std::sqrt((0.04 + 0.01) / 4);
    EXPECT_NEAR(s.rule_rms, rule_rms, 1e-6);
    EXPECT_NEAR(s.slope, 0.5, 1e-6);
    EXPECT_NEAR(s.carried_rms, 0.5 * rule_rms, 1e-6);
    EXPECT_NEAR(s.rest_rms, std::sqrt(0.02 / 4), 1e-6);
    const ImageDifference d = CompareImages(im, ref, ToneMap{});
    EXPECT_NEAR(d.relative_rms * d.relative_rms,
                s.carried_rms * s.carried_rms + s.rest_rms * s.rest_rms, 1e-9);
    // The rule picture itself carries all of its loss; a rule that loses nothing (a flat
    // scene) leaves the whole error to the rest.
    EXPECT_NEAR(SplitByRule(rule, ref, rule, ToneMap{}).slope, 1, 1e-9);
    EXPECT_NEAR(SplitByRule(rule, ref, rule, ToneMap{}).rest_rms, 0, 1e-6);
    ComparedImage rounded = ref;
    rounded.rgb[0] = std::nextafter(1.f, 2.f);  // a flat scene's rule: float rounding only
    const RuleSplit exact = SplitByRule(im, ref, rounded, ToneMap{});
    EXPECT_EQ(exact.slope, 0);
    EXPECT_EQ(exact.carried_rms, 0);
    EXPECT_NEAR(exact.rest_rms, d.relative_rms, 1e-9);
}

TEST(ImageCompare, ReadsExrAndPngAndRejectsBadInput) {
    const fs::path dir = fs::temp_directory_path() / ("mebake-imgcmp-" + std::to_string(getpid()));
    fs::create_directories(dir);
    const std::string exr = (dir / "a.exr").string(), png = (dir / "a.png").string();
    io::WriteExr(exr, 2, 1, {"R", "G", "B", "A"}, std::vector<float>{1, 2, 3, 1, 4, 5, 6, 0});
    io::WritePng(png, 3, 1, 3, std::vector<uint8_t>(9, 255));
    const ComparedImage e = ReadComparedImage(exr);
    EXPECT_TRUE(e.linear);
    EXPECT_EQ(e.rgb[4], 5.f);
    EXPECT_EQ(e.coverage[1], 0.f);
    const ComparedImage p = ReadComparedImage(png);
    EXPECT_FALSE(p.linear);
    EXPECT_EQ(p.rgb[0], 1.f);
    try {
        CompareImages(e, p, ToneMap{});
        FAIL() << "sizes differ";
    } catch (const Error& err) {
        EXPECT_EQ(err.kind(), ErrorKind::Input);
        EXPECT_NE(std::string(err.what()).find("a.png"), std::string::npos);
    }
    EXPECT_THROW(ReadComparedImage((dir / "missing.exr").string()), Error);
    EXPECT_THROW(ReadComparedImage((dir / "a.tif").string()), Error);
    fs::remove_all(dir);
}

}  // namespace
}  // namespace mebake::output
