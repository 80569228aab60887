// `mebake export` and `mebake render`: option parsing, then one call into output/.
#include "app/export_commands.h"
#include "core/error.h"
#include "core/parallel.h"
#include "output/export_job.h"

#include <cmath>
#include <cstdio>

namespace mebake::app {

namespace {

output::ToneMap ParseTone(double exposure, const std::string& curve) {
    auto c = output::ParseToneCurve(curve);
    if (!c)
        UsageError("--tonemap '{}': expected filmic, reinhard or clamp", curve);
    return output::ToneMap{float(exposure), *c};
}

io::ExrCompression ParseCompression(const std::string& s) {
    if (s == "zip")
        return io::ExrCompression::Zip;
    if (s == "piz")
        return io::ExrCompression::Piz;
    if (s == "none")
        return io::ExrCompression::None;
    UsageError("--compression '{}': expected zip, piz or none", s);
}

}  // namespace

Vec3d ToVec3(const std::vector<double>& v, const char* option) {
    if (v.size() != 3)
        UsageError("{}: expected three numbers", option);
    for (double x : v)
        if (!std::isfinite(x))
            UsageError("{}: not a finite number", option);
    return Vec3d(v[0], v[1], v[2]);
}

int RunExport(const ExportCommand& c) {
    ThreadLimit limit(c.threads);
    output::ExportJobOptions o;
    o.dir = c.dir;
    o.lightmap = c.lightmap;
    o.irradiance = c.irradiance;
    o.mesh = c.mesh;
    o.vertex_colors = c.vertex_colors;
    o.stats = c.stats;
    o.atlas.max_size = c.max_atlas;
    o.atlas.gutter = c.gutter;
    o.atlas.power_of_two = !c.npot;
    o.maps.tone = ParseTone(c.exposure, c.tonemap);
    o.maps.exr_type = c.float_output ? io::ExrPixelType::Float : io::ExrPixelType::Half;
    o.maps.compression = ParseCompression(c.compression);
    o.tone_curve = c.tonemap;
    o.glb_mode = c.unlit ? io::GlbLightMapMode::Unlit : io::GlbLightMapMode::Emissive;
    o.float_colors = c.float_output;
    o.stitch = !c.no_stitch;
    o.force = c.force;
    o.memory = ParseMemory(c.memory);
    output::RunExportJob(o);
    return 0;
}

int RunRender(const RenderCommand& c) {
    ThreadLimit limit(c.threads);
    output::RenderJobOptions o;
    {
        char x = 0, extra = 0;
        if (std::sscanf(c.size.c_str(), "%d%c%d%c", &o.width, &x, &o.height, &extra) != 3 ||
            (x != 'x' && x != 'X'))
            UsageError("--size '{}': expected WIDTHxHEIGHT, e.g. 800x600", c.size);
    }
    o.tone = ParseTone(c.exposure, c.tonemap);
    o.dir = c.dir;
    o.output = c.output;
    o.fov = c.fov;
    if (!c.eye.empty())
        o.eye = ToVec3(c.eye, "--eye");
    if (!c.target.empty())
        o.target = ToVec3(c.target, "--target");
    if (!c.up.empty())
        o.up = ToVec3(c.up, "--up");
    o.glossy = c.glossy;
    o.samples = c.samples;
    if (!c.background.empty())
        o.background = Vec3f(ToVec3(c.background, "--background"));
    o.exr_type = c.float_output ? io::ExrPixelType::Float : io::ExrPixelType::Half;
    o.stitch = !c.no_stitch;
    o.force = c.force;
    output::RunRenderJob(o);
    return 0;
}

}  // namespace mebake::app
