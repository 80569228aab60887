// Comparing two pictures of the same view pixel by pixel: a bake's render against the
// path-traced reference picture (reference/reference_image.h), or any two renders.
//
// Pictures are linear radiance (EXR: R G B, optional coverage A and standard errors se.R
// se.G se.B as `mebake reference --image` writes them) or display values (PNG, 8-bit sRGB
// as code / 255). Two linear pictures are compared in radiance; if either is a PNG, the EXR
// is tone-mapped first and both are compared in display values.
//
// Pixels counted: those fully covered by the object (coverage 1) in every picture, or mask,
// that has a coverage channel; without any, all pixels (the background too). Over them,
// with err(p) = sqrt(mean over colours of (a - ref)^2):
//   relative RMS   sqrt(mean err^2) / mean of the reference (over pixels and colours),
//   p95, max       of err / mean of the reference,
//   bias           mean of (a - ref) over pixels and colours / mean of the reference: the
//                  part of the RMS that is one level (too dark or too bright everywhere),
//   display RMS    of the tone-mapped sRGB difference (0..1), what a viewer sees,
//   noise          sqrt(mean se^2) / mean, the reference's own noise (when it has se), and
//                  the corrected RMS sqrt(max(0, RMS^2 - noise^2)), the error left to the bake;
//   border RMS     the relative RMS next to chart borders and away from them, when the
//                  reference has a chart channel (the reference picture's EXR does);
//   silhouette RMS the relative RMS over the pixels whose 3 x 3 block reaches a pixel not
//                  compared (the background: the object's outline, where the view grazes
//                  the surface), when a coverage channel limits the pixels.
#pragma once

#include "output/tonemap.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace mebake::output {

struct ComparedImage {
    std::string path;
    int width = 0, height = 0;
    bool linear = true;           // EXR radiance; false: PNG display values in [0, 1]
    std::vector<float> rgb;       // 3 per pixel
    std::vector<float> coverage;  // empty: none
    std::vector<float> se;        // 3 per pixel; empty: none
    std::vector<int32_t> chart;   // chart seen per pixel, -1 none; empty: no chart channel
};

// Reads a .exr (needs R G B) or .png (RGB or RGBA; alpha ignored). Throws Error(Io) when
// missing, Error(Input) naming the file when unreadable or lacking R G B, Error(Usage)
// for another extension.
ComparedImage ReadComparedImage(const std::string& path);

struct ImageDifference {
    uint64_t pixels = 0;   // compared
    bool masked = false;   // pixels came from a coverage channel
    bool display = false;  // compared in display values (a PNG was involved)
    double mean_reference = 0;
    double relative_rms = 0, relative_p95 = 0, relative_max = 0;
    double relative_bias = 0;  // signed
    double display_rms = 0;  // sRGB 0..1
    std::optional<double> noise_rms, corrected_rms;
    // With a chart channel: the relative RMS over pixels next to a chart border (a
    // neighbour of the 3 x 3 block sees another chart) and over the others.
    uint64_t border_pixels = 0;
    std::optional<double> border_rms, interior_rms;
    uint64_t silhouette_pixels = 0;
    std::optional<double> silhouette_rms;
};

// `image` against `reference` (the denominator's picture). mask: optional third picture
// whose coverage channel also limits the pixels. Throws Error(Input) naming both files when
// the sizes differ, or when no pixel is left to compare.
ImageDifference CompareImages(const ComparedImage& image, const ComparedImage& reference,
                              const ToneMap& tone, const ComparedImage* mask = nullptr);

// How much of an image's error is the display rule's loss (docs/accuracy.md, "Pictures").
// `rule` is the reference's rule picture (`reference --rule-image`: the light map's display
// rule applied to the path-traced vector irradiance E at the same hits). With d = image -
// reference and l = rule - reference over the compared pixels and colours, the slope
// k = <d, l> / <l, l> is how much of the rule's loss the image carries (1: all of it, as a
// bake whose receivers gathered E over the geometric normal's hemisphere would; 0: none),
// and d splits into orthogonal parts, RMS^2 = carried^2 + rest^2:
//   carried  |k| x the rule picture's RMS: the image's error along the rule's loss,
//   rest     RMS of d - k l: the rest (the field's own error and the reference's noise).
// All relative to the reference's mean, as CompareImages; k = 0 when the rule picture
// loses nothing but float rounding (relative RMS <= 1e-5: a flat scene). Throws as
// CompareImages.
struct RuleSplit {
    double rule_rms = 0;  // the rule picture against the reference
    double slope = 0;     // k
    double carried_rms = 0, rest_rms = 0;
};
RuleSplit SplitByRule(const ComparedImage& image, const ComparedImage& reference,
                      const ComparedImage& rule, const ToneMap& tone,
                      const ComparedImage* mask = nullptr);

// A false-colour picture of the signed display error image - reference per pixel (mean
// over colours of the sRGB values): blue below, white equal, red above, saturating at
// +-range; pixels not compared show the reference darkened in grey. With `borders`, the
// chart borders of the reference's chart channel are drawn in black. 8-bit RGB.
std::vector<uint8_t> DifferencePicture(const ComparedImage& image, const ComparedImage& reference,
                                       const ToneMap& tone, double range,
                                       const ComparedImage* mask = nullptr, bool borders = false);

}  // namespace mebake::output
