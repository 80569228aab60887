// A path-traced reference picture: the diffuse radiance B/pi that a pinhole camera sees,
// estimated independently of the solver, to compare pixel by pixel with `mebake render`.
//
// Each pixel sends the same k x k primary rays as `render --samples k` (core/camera.h).
// A front-facing hit becomes a reference point whose B is estimated by the point estimator
// of reference.h (next-event estimation, cosine/uniform mixture, Russian roulette), with
// the paths of the point seeded by its pixel and stratum index, so the picture is the same
// for any thread count. Rays that hit the back of a triangle see black and rays that miss
// see the background (the given colour, else the sky as render shows it: uniform, or CIE
// overcast with elevation clamped at the horizon), as in output/render.h.
//
// Noise: the points run the progressive rounds of ReferenceTracer::Estimate, so every
// pixel gets samples until the standard error of its B meets the target relative error
// (with the floor of ReferenceOptions) or the sample or time limit stops it. The picture
// carries each pixel's standard error so that a comparison can separate the reference's
// noise from the bake's error.
#pragma once

#include "core/camera.h"
#include "reference/reference.h"

#include <functional>
#include <optional>
#include <vector>

namespace mebake::reference {

struct ReferenceImageOptions {
    Camera camera;
    int strata = 1;                   // primary rays per pixel and axis (render --samples)
    std::optional<Vec3f> background;  // radiance of missed rays; default: the sky
    ReferenceOptions paths;           // seed, samples, target, time limit
};

struct ReferenceImage {
    int width = 0, height = 0;
    std::vector<float> rgb;         // radiance (W/m^2/sr), row-major from the top, 3 per pixel
    std::vector<float> se;          // standard error of rgb, 3 per pixel
    std::vector<float> coverage;    // fraction of the pixel's primary rays that hit a surface
    std::vector<uint32_t> samples;  // paths per pixel (over its front-facing rays)
    std::vector<int32_t> chart;     // chart hit by the pixel's first ray; -1: a miss
    // The light map's display rule applied to the estimated vector irradiance E at the same
    // hits, (pi Le + rho (n . E)+) / pi, 3 per pixel (background and black as rgb): what a
    // bake whose field were exact would show, so that picture error splits into what the
    // rule loses (rule against rgb) and what the bake's field gets wrong (bake against rule).
    std::vector<float> rule;
    ReferenceStats stats;
    uint64_t points = 0;  // front-facing primary hits whose B was estimated
    // Noise of the picture: RMS over covered pixels of the standard error of the
    // radiance (mean over colours), relative to the mean radiance of those pixels.
    double relative_noise = 0;
    uint64_t covered = 0;  // pixels with coverage 1
};

// Throws Error(Usage) for a degenerate camera or strata outside [1, 16].
ReferenceImage RenderReferenceImage(const ReferenceMesh& mesh, const solve::Scene& scene,
                                    const ReferenceTracer& tracer,
                                    const ReferenceImageOptions& options,
                                    const std::function<void(int, uint64_t)>& progress = {});

}  // namespace mebake::reference
