// `mebake compare IMAGE REFERENCE`: two pictures of the same view scored pixel by pixel
// (output/image_compare.h), with an optional false-colour difference PNG.
#include "app/reference_commands.h"
#include "core/error.h"
#include "core/log.h"
#include "io/byte_stream.h"
#include "io/png_writer.h"
#include "output/image_compare.h"

#include <cctype>
#include <filesystem>
#include <nlohmann/json.hpp>

namespace mebake::app {

namespace {

bool IsPicture(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& ch : ext)
        ch = char(std::tolower(static_cast<unsigned char>(ch)));
    return (ext == ".png" || ext == ".exr") && !std::filesystem::is_directory(path);
}

}  // namespace

bool IsPicturePair(const CompareCommand& c) {
    return IsPicture(c.dir) || IsPicture(c.reference);
}

int RunCompareImages(const CompareCommand& c) {
    if (!IsPicture(c.dir) || !IsPicture(c.reference))
        UsageError("compare: give two pictures (.png or .exr) or a bake directory and a "
                   "reference JSON, not {} and {}",
                   c.dir, c.reference);
    const auto curve = output::ParseToneCurve(c.tonemap);
    if (!curve)
        UsageError("--tonemap '{}': expected filmic, reinhard or clamp", c.tonemap);
    const output::ToneMap tone{float(c.exposure), *curve};
    const output::ComparedImage image = output::ReadComparedImage(c.dir);
    const output::ComparedImage ref = output::ReadComparedImage(c.reference);
    std::optional<output::ComparedImage> mask;
    if (!c.mask.empty())
        mask = output::ReadComparedImage(c.mask);
    const output::ComparedImage* m = mask ? &*mask : nullptr;
    if (c.borders && ref.chart.empty())
        UsageError("--borders: {} has no chart channel (a `mebake reference --image` EXR has)",
                   c.reference);
    const output::ImageDifference d = output::CompareImages(image, ref, tone, m);
    std::optional<output::RuleSplit> split;
    if (!c.rule.empty())
        split = output::SplitByRule(image, ref, output::ReadComparedImage(c.rule), tone, m);
    if (!d.masked)
        spdlog::warn("compare: no coverage channel (A) in either picture or --mask: every pixel, "
                     "the background too, is compared");
    if (!c.diff.empty()) {
        const auto bytes = output::DifferencePicture(image, ref, tone, c.diff_range, m, c.borders);
        io::WritePng(c.diff, image.width, image.height, 3, bytes);
    }
    std::string noise;
    if (d.noise_rms)
        noise = fmt::format(" (reference noise {:.2f}%, without it {:.2f}%)", 100 * *d.noise_rms,
                            100 * *d.corrected_rms);
    if (d.border_rms)
        noise += fmt::format("; next to chart borders ({} pixels) {:.2f}%, elsewhere {:.2f}%",
                             d.border_pixels, 100 * *d.border_rms, 100 * *d.interior_rms);
    if (d.silhouette_rms)
        noise += fmt::format("; at the silhouette ({} pixels) {:.2f}%", d.silhouette_pixels,
                             100 * *d.silhouette_rms);
    if (split)
        noise += fmt::format("; the rule picture {:.2f}%, of it carried x{:.2f}: {:.2f}%, the rest "
                             "{:.2f}%",
                             100 * split->rule_rms, split->slope, 100 * split->carried_rms,
                             100 * split->rest_rms);
    spdlog::info("{} vs {}: {} pixels, relative RMS {:.2f}%{}, bias {:+.2f}%, p95 {:.2f}%, "
                 "max {:.1f}%; display RMS {:.2f}% ({})",
                 c.dir, c.reference, d.pixels, 100 * d.relative_rms, noise,
                 100 * d.relative_bias, 100 * d.relative_p95, 100 * d.relative_max,
                 100 * d.display_rms,
                 d.display ? "display values" : "radiance");
    nlohmann::json j;
    j["image"] = c.dir;
    j["reference"] = c.reference;
    j["pixels"] = d.pixels;
    j["masked"] = d.masked;
    j["compared_in"] = d.display ? "display" : "radiance";
    j["mean_reference"] = d.mean_reference;
    j["relative_rms"] = d.relative_rms;
    j["relative_p95"] = d.relative_p95;
    j["relative_max"] = d.relative_max;
    j["relative_bias"] = d.relative_bias;
    j["display_rms"] = d.display_rms;
    if (d.noise_rms) {
        j["reference_noise_rms"] = *d.noise_rms;
        j["corrected_rms"] = *d.corrected_rms;
    }
    if (d.border_rms) {
        j["border_pixels"] = d.border_pixels;
        j["border_rms"] = *d.border_rms;
        j["interior_rms"] = *d.interior_rms;
    }
    if (d.silhouette_rms) {
        j["silhouette_pixels"] = d.silhouette_pixels;
        j["silhouette_rms"] = *d.silhouette_rms;
    }
    if (split) {
        j["rule"] = c.rule;
        j["rule_rms"] = split->rule_rms;
        j["rule_slope"] = split->slope;
        j["rule_carried_rms"] = split->carried_rms;
        j["rule_rest_rms"] = split->rest_rms;
    }
    if (!c.diff.empty())
        j["diff"] = c.diff;
    auto out = io::OutputStream::Open(c.output);
    out->Write(j.dump(1) + "\n");
    out->Commit();
    return 0;
}

}  // namespace mebake::app
