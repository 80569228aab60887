#include "output/image_compare.h"

#include "core/error.h"
#include "io/exr_writer.h"
#include "io/png_writer.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

namespace mebake::output {

namespace {

std::string Extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& ch : ext)
        ch = char(std::tolower(static_cast<unsigned char>(ch)));
    return ext;
}

// The sRGB display value (0..1) of channel c of pixel p.
float Display(const ComparedImage& im, size_t p, int c, const ToneMap& tone) {
    const float v = im.rgb[3 * p + size_t(c)];
    return im.linear ? EncodeSrgb(ApplyToneCurve(v, tone)) : v;
}

bool Counted(const ComparedImage& im, size_t p) {
    return im.coverage.empty() || im.coverage[p] >= 1.f;
}

// Whether pixel p sees a chart and a pixel of its 3 x 3 block another one.
bool NearChartBorder(const ComparedImage& im, size_t p) {
    if (im.chart.empty() || im.chart[p] < 0)
        return false;
    const int x = int(p % size_t(im.width)), y = int(p / size_t(im.width));
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            const int u = x + dx, v = y + dy;
            if (u < 0 || v < 0 || u >= im.width || v >= im.height)
                continue;
            const int32_t c = im.chart[size_t(v) * size_t(im.width) + size_t(u)];
            if (c >= 0 && c != im.chart[p])
                return true;
        }
    return false;
}

// Whether compared pixel p has a pixel of its 3 x 3 block that is not compared (the
// background, or the frame's edge): the object's silhouette, where the view grazes the
// surface.
template <typename IsCounted>
bool OnSilhouette(int width, int height, size_t p, const IsCounted& counted) {
    const int x = int(p % size_t(width)), y = int(p / size_t(width));
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            const int u = x + dx, v = y + dy;
            if (u < 0 || v < 0 || u >= width || v >= height ||
                !counted(size_t(v) * size_t(width) + size_t(u)))
                return true;
        }
    return false;
}

void CheckSameSize(const ComparedImage& a, const ComparedImage& b) {
    if (a.width != b.width || a.height != b.height)
        InputError({b.path}, "{}x{} pixels, but {} has {}x{}", b.width, b.height, a.path, a.width,
                   a.height);
}

}  // namespace

ComparedImage ReadComparedImage(const std::string& path) {
    ComparedImage im;
    im.path = path;
    const std::string ext = Extension(path);
    if (ext == ".png") {
        const io::PngImage png = io::ReadPng(path);
        im.width = png.width;
        im.height = png.height;
        im.linear = false;
        const size_t n = size_t(png.width) * size_t(png.height);
        const size_t ch = size_t(png.channels);
        if (ch < 3)
            InputError({path}, "a grey PNG; expected RGB");
        im.rgb.resize(n * 3);
        for (size_t p = 0; p < n; ++p)
            for (size_t c = 0; c < 3; ++c)
                im.rgb[3 * p + c] = float(png.pixels[p * ch + c]) / 255.f;
        return im;
    }
    if (ext != ".exr")
        UsageError("{}: expected a .exr or .png picture", path);
    const io::ExrImage exr = io::ReadExr(path);
    im.width = exr.width;
    im.height = exr.height;
    const int r = exr.Channel("R"), g = exr.Channel("G"), b = exr.Channel("B");
    if (r < 0 || g < 0 || b < 0)
        InputError({path}, "no R, G and B channels");
    const int a = exr.Channel("A"), chart = exr.Channel("chart");
    const int se[3] = {exr.Channel("se.R"), exr.Channel("se.G"), exr.Channel("se.B")};
    const bool has_se = se[0] >= 0 && se[1] >= 0 && se[2] >= 0;
    const size_t n = size_t(exr.width) * size_t(exr.height);
    im.rgb.resize(n * 3);
    if (a >= 0)
        im.coverage.resize(n);
    if (has_se)
        im.se.resize(n * 3);
    if (chart >= 0)
        im.chart.resize(n);
    for (int y = 0; y < exr.height; ++y)
        for (int x = 0; x < exr.width; ++x) {
            const size_t p = size_t(y) * size_t(exr.width) + size_t(x);
            const int rgb[3] = {r, g, b};
            for (int c = 0; c < 3; ++c) {
                const float v = exr.At(x, y, rgb[c]);
                if (!std::isfinite(v))
                    InputError({path}, "pixel {},{} is not finite", x, y);
                im.rgb[3 * p + size_t(c)] = v;
                if (has_se)
                    im.se[3 * p + size_t(c)] = exr.At(x, y, se[c]);
            }
            if (a >= 0)
                im.coverage[p] = exr.At(x, y, a);
            if (chart >= 0)
                im.chart[p] = int32_t(exr.At(x, y, chart));
        }
    return im;
}

ImageDifference CompareImages(const ComparedImage& image, const ComparedImage& ref,
                              const ToneMap& tone, const ComparedImage* mask) {
    CheckSameSize(image, ref);
    if (mask)
        CheckSameSize(image, *mask);
    ImageDifference d;
    d.display = !image.linear || !ref.linear;
    d.masked =
        !image.coverage.empty() || !ref.coverage.empty() || (mask && !mask->coverage.empty());
    const size_t n = size_t(ref.width) * size_t(ref.height);
    // Compared values: radiance, or display values when a PNG is involved.
    auto value = [&](const ComparedImage& im, size_t p, int c) {
        return d.display ? double(Display(im, p, c, tone)) : double(im.rgb[3 * p + size_t(c)]);
    };
    std::vector<double> err;  // per counted pixel, in compared units
    double sum_ref = 0, sum_err2 = 0, sum_disp2 = 0, sum_se2 = 0, sum_diff = 0;
    double border_err2 = 0, interior_err2 = 0, silhouette_err2 = 0;
    const bool has_se = !d.display && (!ref.se.empty() || !image.se.empty());
    auto counted = [&](size_t p) {
        return Counted(image, p) && Counted(ref, p) && (!mask || Counted(*mask, p));
    };
    for (size_t p = 0; p < n; ++p) {
        if (!counted(p))
            continue;
        double e2 = 0, disp2 = 0;
        for (int c = 0; c < 3; ++c) {
            const double a = value(image, p, c), b = value(ref, p, c);
            e2 += (a - b) * (a - b) / 3;
            sum_ref += b / 3;
            sum_diff += (a - b) / 3;
            const double da = Display(image, p, c, tone) - Display(ref, p, c, tone);
            disp2 += da * da / 3;
            for (const ComparedImage* im : {&image, &ref})
                if (has_se && !im->se.empty())
                    sum_se2 += double(im->se[3 * p + size_t(c)]) * im->se[3 * p + size_t(c)] / 3;
        }
        err.push_back(std::sqrt(e2));
        sum_err2 += e2;
        if (NearChartBorder(ref, p)) {
            border_err2 += e2;
            ++d.border_pixels;
        } else {
            interior_err2 += e2;
        }
        if (d.masked && OnSilhouette(ref.width, ref.height, p, counted)) {
            silhouette_err2 += e2;
            ++d.silhouette_pixels;
        }
        sum_disp2 += disp2;
    }
    d.pixels = err.size();
    if (d.pixels == 0)
        InputError({ref.path}, "no pixel covered by the object in both it and {}", image.path);
    const double np = double(d.pixels);
    d.mean_reference = sum_ref / np;
    if (!(d.mean_reference > 0))
        InputError({ref.path}, "the reference is black where it is compared");
    d.relative_rms = std::sqrt(sum_err2 / np) / d.mean_reference;
    d.relative_bias = sum_diff / np / d.mean_reference;
    d.display_rms = std::sqrt(sum_disp2 / np);
    std::sort(err.begin(), err.end());
    d.relative_max = err.back() / d.mean_reference;
    d.relative_p95 =
        err[std::min(err.size() - 1, size_t(std::ceil(0.95 * np)) - 1)] / d.mean_reference;
    if (!ref.chart.empty() && d.border_pixels > 0 && d.border_pixels < d.pixels) {
        d.border_rms = std::sqrt(border_err2 / double(d.border_pixels)) / d.mean_reference;
        d.interior_rms =
            std::sqrt(interior_err2 / double(d.pixels - d.border_pixels)) / d.mean_reference;
    }
    if (d.silhouette_pixels > 0)
        d.silhouette_rms =
            std::sqrt(silhouette_err2 / double(d.silhouette_pixels)) / d.mean_reference;
    if (has_se) {
        d.noise_rms = std::sqrt(sum_se2 / np) / d.mean_reference;
        d.corrected_rms =
            std::sqrt(std::max(0.0, d.relative_rms * d.relative_rms - *d.noise_rms * *d.noise_rms));
    }
    return d;
}

RuleSplit SplitByRule(const ComparedImage& image, const ComparedImage& ref,
                      const ComparedImage& rule, const ToneMap& tone, const ComparedImage* mask) {
    CheckSameSize(image, ref);
    CheckSameSize(image, rule);
    if (mask)
        CheckSameSize(image, *mask);
    const bool display = !image.linear || !ref.linear || !rule.linear;
    auto value = [&](const ComparedImage& im, size_t p, int c) {
        return display ? double(Display(im, p, c, tone)) : double(im.rgb[3 * p + size_t(c)]);
    };
    // Sums over the pixels CompareImages counts (and the rule picture covers), in pixel order.
    double sum_ref = 0, dd = 0, dl = 0, ll = 0;
    uint64_t pixels = 0;
    const size_t n = size_t(ref.width) * size_t(ref.height);
    for (size_t p = 0; p < n; ++p) {
        if (!Counted(image, p) || !Counted(ref, p) || !Counted(rule, p) ||
            (mask && !Counted(*mask, p)))
            continue;
        ++pixels;
        for (int c = 0; c < 3; ++c) {
            const double r = value(ref, p, c);
            const double d = value(image, p, c) - r, l = value(rule, p, c) - r;
            sum_ref += r;
            dd += d * d;
            dl += d * l;
            ll += l * l;
        }
    }
    if (pixels == 0)
        InputError({ref.path}, "no pixel covered by the object in it, {} and {}", image.path,
                   rule.path);
    const double values = 3 * double(pixels), mean = sum_ref / values;
    if (!(mean > 0))
        InputError({ref.path}, "the reference is black where it is compared");
    RuleSplit s;
    s.rule_rms = std::sqrt(ll / values) / mean;
    // A rule that loses nothing but float rounding (every face flat: the two pictures agree
    // to ~1e-7) has no direction to carry: k would be noise over rounding.
    constexpr double kNoLoss = 1e-5;
    s.slope = s.rule_rms > kNoLoss ? dl / ll : 0;
    s.carried_rms = std::abs(s.slope) * s.rule_rms;
    // |d - k l|^2 = |d|^2 - k <d, l> (least squares: the residual is orthogonal to l).
    s.rest_rms = std::sqrt(std::max(0.0, dd - s.slope * dl) / values) / mean;
    return s;
}

std::vector<uint8_t> DifferencePicture(const ComparedImage& image, const ComparedImage& ref,
                                       const ToneMap& tone, double range, const ComparedImage* mask,
                                       bool borders) {
    CheckSameSize(image, ref);
    if (mask)
        CheckSameSize(image, *mask);
    if (!(range > 0))
        UsageError("--diff-range {}: expected a positive number", range);
    const size_t n = size_t(ref.width) * size_t(ref.height);
    std::vector<uint8_t> out(n * 3);
    for (size_t p = 0; p < n; ++p) {
        double a = 0, b = 0;
        for (int c = 0; c < 3; ++c) {
            a += Display(image, p, c, tone) / 3;
            b += Display(ref, p, c, tone) / 3;
        }
        uint8_t* o = &out[3 * p];
        if (!Counted(image, p) || !Counted(ref, p) || (mask && !Counted(*mask, p))) {
            const auto grey = uint8_t(std::lround(std::clamp(b, 0.0, 1.0) * 80));
            o[0] = o[1] = o[2] = grey;
            continue;
        }
        if (borders && !ref.chart.empty() && ref.chart[p] >= 0) {
            // One-pixel lines: where the chart differs from the right or lower neighbour.
            const size_t x = p % size_t(ref.width), y = p / size_t(ref.width);
            const bool right = x + 1 < size_t(ref.width) && ref.chart[p + 1] >= 0 &&
                               ref.chart[p + 1] != ref.chart[p];
            const bool below = y + 1 < size_t(ref.height) &&
                               ref.chart[p + size_t(ref.width)] >= 0 &&
                               ref.chart[p + size_t(ref.width)] != ref.chart[p];
            if (right || below) {
                o[0] = o[1] = o[2] = 0;
                continue;
            }
        }
        // Diverging map: white at 0, red where the image is brighter, blue where darker.
        const double t = std::clamp((a - b) / range, -1.0, 1.0);
        const auto fade = uint8_t(std::lround(255 * (1 - std::abs(t))));
        o[0] = t >= 0 ? 255 : fade;
        o[1] = fade;
        o[2] = t <= 0 ? 255 : fade;
    }
    return out;
}

}  // namespace mebake::output
