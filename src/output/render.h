// `mebake render`: a view of the baked solution through a pinhole camera. Primary rays are
// traced with Embree against the full-resolution mesh of the tiles (one geometry per
// chart, so a hit's geometry id is the chart and its primitive id the tile triangle); the
// hit is shaded with the hit barycentrics' uv, normal and colour (bake_view.h ChartShader):
// radiance B/pi, or with `glossy` the seed paper's view-dependent approximation
// L ~ Le + |E| fr(x, x + E, z). A back-face hit is black: light is solved on the side the
// triangles face, and nothing lights the back (the reference path tracer agrees). Rays that miss see the background: the
// given colour, else the scene's sky radiance (uniform, or CIE overcast by elevation).
//
// Out of core, in two passes over bands of rows: the camera samples are traced against
// groups of consecutive charts of at most `group_triangles` triangles, one Embree scene at
// a time, each sample keeping its closest hit (a tie keeps the lower chart id); then the
// hit samples are shaded chart by chart, one tile and shader per worker in flight.
// Memory: one group's scene (~55 B per triangle, 1M triangles by default) and 36 B per
// sample of a band (at most 1M samples), whatever the mesh.
//
// Deterministic: each sample depends on its own ray and the fixed groups only; rows and
// charts run in parallel through core/parallel.h, each writing its own slots.
#pragma once

#include "core/camera.h"
#include "core/vec.h"
#include "io/exr_writer.h"
#include "output/bake_view.h"
#include "output/tonemap.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace mebake::output {

using mebake::Camera;  // core/camera.h: shared with the reference picture

struct RenderOptions {
    Camera camera;
    bool glossy = false;
    int samples = 1;                  // per pixel and axis: samples^2 stratified rays
    std::optional<Vec3f> background;  // radiance of missed rays; default: the sky
    // Triangles per Embree scene. Fixed, not from --memory: a tie between charts at the same
    // distance resolves by the grouping, so the same groups give the same bytes.
    uint64_t group_triangles = uint64_t(1) << 20;
};

struct RenderedImage {
    int width = 0, height = 0;
    std::vector<float> rgb;  // linear radiance, row-major from the top row, 3 per pixel
    uint64_t rays = 0, hits = 0;

    Vec3f At(int x, int y) const {
        const float* p = &rgb[(size_t(y) * size_t(width) + size_t(x)) * 3];
        return Vec3f(p[0], p[1], p[2]);
    }
};

// The default view: a three-quarter view from the key light's side of the default rig
// (solve/scene.cpp), slightly above, at the distance where the object (its tiles' vertices)
// fills 85 % of the frame's height or width (the ground of --ground is left out of the framing).
Camera DefaultCamera(const BakeView& view, int width, int height, double fov = 50);

// Throws Error(Usage) for a degenerate camera (eye = target, up parallel to the view,
// fov outside (0, 180), size outside [1, 16384]).
RenderedImage Render(const BakeView& view, const RenderOptions& options);

// To ".exr" (linear radiance, R G B) or ".png" (tone-mapped sRGB); "-" writes EXR.
void WriteRenderedImage(const RenderedImage& image, const std::string& path, const ToneMap& tone,
                        io::ExrPixelType exr_type = io::ExrPixelType::Half);

}  // namespace mebake::output
