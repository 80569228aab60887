// `mebake reference DIR --image OUT`: the path-traced picture of a view
// (reference/reference_image.h), with render's camera options and default view, written as
// a linear EXR (with coverage and per-pixel standard errors) and/or a tone-mapped PNG.
#include "app/export_commands.h"
#include "app/reference_commands.h"
#include "core/error.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/units.h"
#include "io/byte_stream.h"
#include "io/exr_writer.h"
#include "output/bake_view.h"
#include "output/render.h"
#include "reference/reference_image.h"
#include "solve/solution.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

namespace mebake::app {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string Extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    for (char& ch : ext)
        ch = char(std::tolower(static_cast<unsigned char>(ch)));
    return ext;
}

// Render's camera: its default view of the directory (output::DefaultCamera, the very
// function `mebake render` calls), then the given eye, target and up, as RunRenderJob does.
Camera ResolveCamera(const ReferenceCommand& c, const stream::Manifest& m,
                     const solve::Scene& scene) {
    int width = 0, height = 0;
    char x = 0, extra = 0;
    if (std::sscanf(c.size.c_str(), "%d%c%d%c", &width, &x, &height, &extra) != 3 ||
        (x != 'x' && x != 'X'))
        UsageError("--size '{}': expected WIDTHxHEIGHT, e.g. 800x600", c.size);
    output::BakeView view;
    if (fs::exists(solve::SolutionPath(c.dir))) {
        view = output::OpenBakeView(c.dir, output::FieldLoading::OnDemand);
    } else {  // only ingested: the default view needs the bounds and the scene's up
        view.dir = c.dir;
        view.manifest = m;
        view.scene = scene;
    }
    Camera cam = output::DefaultCamera(view, width, height, c.fov);
    if (!c.eye.empty())
        cam.eye = ToVec3(c.eye, "--eye");
    if (!c.look_at.empty())
        cam.target = ToVec3(c.look_at, "--target");
    if (!c.up.empty())
        cam.up = ToVec3(c.up, "--up");
    return cam;
}

// The picture (rgb, with coverage, standard errors and charts in an EXR) or, with rule, the
// display-rule picture (ReferenceImage::rule, with coverage and charts: its noise is not
// estimated).
void WriteImage(const reference::ReferenceImage& img, const std::string& path,
                const output::ToneMap& tone, bool rule = false) {
    const std::vector<float>& rgb = rule ? img.rule : img.rgb;
    if (Extension(path) == ".png") {
        output::RenderedImage r;  // render's PNG writer: the same tone mapping, byte for byte
        r.width = img.width;
        r.height = img.height;
        r.rgb = rgb;
        output::WriteRenderedImage(r, path, tone);
        return;
    }
    if (Extension(path) != ".exr")
        UsageError("--image {}: expected a .exr or .png file name", path);
    const size_t n = size_t(img.width) * size_t(img.height);
    io::ExrOptions eo;
    eo.type = io::ExrPixelType::Float;
    if (rule) {
        std::vector<float> px(n * 5);
        for (size_t p = 0; p < n; ++p) {
            float* o = &px[p * 5];
            o[0] = rgb[3 * p], o[1] = rgb[3 * p + 1], o[2] = rgb[3 * p + 2];
            o[3] = img.coverage[p];
            o[4] = float(img.chart[p]);
        }
        eo.comments = "mebake reference --rule-image: (pi Le + rho (n.E)+)/pi with the path-traced "
                      "vector irradiance E (W/m^2/sr) in R G B, coverage in A, chart of the first "
                      "ray's hit in chart (-1: none)";
        io::WriteExr(path, img.width, img.height, {"R", "G", "B", "A", "chart"}, px, eo);
        return;
    }
    std::vector<float> px(n * 8);
    for (size_t p = 0; p < n; ++p) {
        float* o = &px[p * 8];
        o[0] = rgb[3 * p], o[1] = rgb[3 * p + 1], o[2] = rgb[3 * p + 2];
        o[3] = img.coverage[p];
        o[4] = img.se[3 * p], o[5] = img.se[3 * p + 1], o[6] = img.se[3 * p + 2];
        o[7] = float(img.chart[p]);  // exact below 2^24 charts
    }
    eo.comments = "mebake reference --image: path-traced radiance (W/m^2/sr) in R G B, "
                  "coverage in A, standard error of R G B in se.R se.G se.B, chart of the first "
                  "ray's hit in chart (-1: none)";
    io::WriteExr(path, img.width, img.height, {"R", "G", "B", "A", "se.R", "se.G", "se.B", "chart"},
                 px, eo);
}

// The noisiest covered pixels (relative standard error, mean over colours), worst first.
json NoisyPixels(const reference::ReferenceImage& img, size_t count) {
    struct Noisy {
        double rel;
        size_t pixel;
    };
    std::vector<Noisy> all;
    for (size_t p = 0; p < img.coverage.size(); ++p) {
        const double v = (img.rgb[3 * p] + img.rgb[3 * p + 1] + img.rgb[3 * p + 2]) / 3;
        const double se = (img.se[3 * p] + img.se[3 * p + 1] + img.se[3 * p + 2]) / 3;
        if (img.coverage[p] > 0 && se > 0)
            all.push_back({v > 0 ? se / v : INFINITY, p});
    }
    count = std::min(count, all.size());
    std::partial_sort(all.begin(), all.begin() + ptrdiff_t(count), all.end(),
                      [](const Noisy& a, const Noisy& b) {
                          return a.rel > b.rel || (a.rel == b.rel && a.pixel < b.pixel);
                      });
    json out = json::array();
    for (size_t i = 0; i < count; ++i)
        out.push_back(
            {{"x", all[i].pixel % size_t(img.width)},
             {"y", all[i].pixel / size_t(img.width)},
             {"relative_se", std::isfinite(all[i].rel) ? json(all[i].rel) : json(nullptr)},
             {"samples", img.samples[all[i].pixel]}});
    return out;
}

}  // namespace

int RunReferenceImage(const ReferenceCommand& c) {
    ThreadLimit limit(c.threads);
    const auto tone_curve = output::ParseToneCurve(c.tonemap);
    if (!tone_curve)
        UsageError("--tonemap '{}': expected filmic, reinhard or clamp", c.tonemap);
    const output::ToneMap tone{float(c.exposure), *tone_curve};
    for (const std::string& path : c.images)
        if (Extension(path) != ".png" && Extension(path) != ".exr")
            UsageError("--image {}: expected a .exr or .png file name", path);
    for (const std::string& path : c.rule_images)
        if (Extension(path) != ".png" && Extension(path) != ".exr")
            UsageError("--rule-image {}: expected a .exr or .png file name", path);
    const stream::Manifest m = stream::ReadManifest(c.dir);
    if (m.state != "ingested")
        UsageError("{}: ingest did not finish (state '{}')", c.dir, m.state);
    std::string scene_file = c.scene_file;
    if (scene_file.empty() && fs::exists(c.dir + "/solve/scene.json"))
        scene_file = c.dir + "/solve/scene.json";
    const solve::Scene scene = solve::LoadScene(m, scene_file);

    reference::ReferenceImageOptions opt;
    opt.camera = ResolveCamera(c, m, scene);
    opt.strata = c.strata;
    if (!c.background.empty())
        opt.background = Vec3f(ToVec3(c.background, "--background"));
    opt.paths.seed = c.seed;
    opt.paths.min_samples = c.min_samples;
    opt.paths.max_samples = c.max_samples;
    opt.paths.target_relative_error = c.target;
    opt.paths.time_limit = c.time_limit;

    const reference::ReferenceMesh mesh = reference::LoadReferenceMesh(c.dir, m);
    const reference::ReferenceTracer tracer(mesh, scene);
    const Vec3d& e = opt.camera.eye;
    spdlog::info("reference image: {}x{} from ({:.4g}, {:.4g}, {:.4g}), {} triangles, scene {}",
                 opt.camera.width, opt.camera.height, e.x, e.y, e.z,
                 FormatCount(double(mesh.triangles.size())), scene.description);
    const reference::ReferenceImage img =
        reference::RenderReferenceImage(mesh, scene, tracer, opt, [&](int round, uint64_t done) {
            spdlog::info("  round {}: {} hit points converged", round, done);
        });
    for (const std::string& path : c.images)
        WriteImage(img, path, tone);
    for (const std::string& path : c.rule_images)
        WriteImage(img, path, tone, true);

    uint64_t high = 0;  // covered pixels with relative standard error above 3x the target
    for (size_t p = 0; p < img.coverage.size(); ++p) {
        const double v = (img.rgb[3 * p] + img.rgb[3 * p + 1] + img.rgb[3 * p + 2]) / 3;
        const double se = (img.se[3 * p] + img.se[3 * p + 1] + img.se[3 * p + 2]) / 3;
        if (img.coverage[p] > 0 && se > 3 * c.target * v)
            ++high;
    }
    spdlog::info("reference image: {} hit points, {} paths, {} rays in {} ({}); noise {:.2f}% "
                 "(RMS standard error / mean over {} covered pixels), {} pixels above 3x the "
                 "target",
                 FormatCount(double(img.points)), FormatCount(double(img.stats.paths)),
                 FormatCount(double(img.stats.rays)), FormatSeconds(img.stats.seconds),
                 img.stats.stop, 100 * img.relative_noise, img.covered, high);

    json j;
    j["format"] = "mebake-reference-image-1";
    j["dir"] = c.dir;
    j["images"] = c.images;
    j["scene"] = scene_file.empty() ? "default" : scene_file;
    j["camera"] = {{"eye", {e.x, e.y, e.z}},
                   {"target", {opt.camera.target.x, opt.camera.target.y, opt.camera.target.z}},
                   {"up", {opt.camera.up.x, opt.camera.up.y, opt.camera.up.z}},
                   {"fov", opt.camera.fov},
                   {"width", opt.camera.width},
                   {"height", opt.camera.height},
                   {"aa", opt.strata}};
    j["settings"] = {{"seed", c.seed},
                     {"min_samples", c.min_samples},
                     {"max_samples", c.max_samples},
                     {"target_relative_error", c.target},
                     {"time_limit", c.time_limit}};
    j["stats"] = {{"rounds", img.stats.rounds},
                  {"hit_points", img.points},
                  {"paths", img.stats.paths},
                  {"rays", img.stats.rays},
                  {"seconds", img.stats.seconds},
                  {"converged", img.stats.converged},
                  {"stop", img.stats.stop},
                  {"covered_pixels", img.covered},
                  {"relative_noise", img.relative_noise},
                  {"pixels_above_3x_target", high}};
    j["noisiest_pixels"] = NoisyPixels(img, 10);
    auto out = io::OutputStream::Open(c.output);
    out->Write(j.dump(1) + "\n");
    out->Commit();
    return 0;
}

}  // namespace mebake::app
