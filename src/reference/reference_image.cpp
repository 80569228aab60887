#include "reference/reference_image.h"

#include "core/error.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mebake::reference {

namespace {

// What a camera ray that misses sees: the rule render uses too (solve::SkyRadiance), which shows the
// overcast sky's horizon value below the horizon instead of black.
Vec3f Background(const solve::Scene& scene, const std::optional<Vec3f>& background,
                 const Vec3f& dir) {
    return background ? *background : solve::SkyRadiance(scene.sky, dir);
}

enum class RayEnd : uint8_t { Miss, Back, Front };

// Every primary ray's outcome, in ray order (pixel-major, then strata), each in its own
// slot: traced row by row in parallel.
struct PrimaryRays {
    struct FirstHit {
        uint32_t triangle = 0;
        float u = 0, v = 0;
    };
    std::vector<RayEnd> end;
    std::vector<Vec3f> dir;
    std::vector<FirstHit> first;  // triangle (of any hit) and barycentrics (of front hits)
};

PrimaryRays TracePrimaryRays(const ReferenceTracer& tracer, const PinholeRays& rays, int k) {
    const Camera& cam = rays.camera();
    const int w = cam.width;
    const size_t per_pixel = size_t(k) * size_t(k);
    const size_t n_rays = size_t(w) * size_t(cam.height) * per_pixel;
    PrimaryRays pr;
    pr.end.assign(n_rays, RayEnd::Miss);
    pr.dir.resize(n_rays);
    pr.first.resize(n_rays);
    ParallelFor(0, cam.height, [&](int64_t py) {
        const size_t row = size_t(py) * size_t(w) * per_pixel;
        std::vector<solve::Segment> segs(size_t(w) * per_pixel);
        std::vector<solve::Hit> hits(segs.size());
        for (int px = 0, r = 0; px < w; ++px)
            for (int sy = 0; sy < k; ++sy)
                for (int sx = 0; sx < k; ++sx, ++r) {
                    const Vec3f d = rays.Direction(px, int(py), sx, sy, k);
                    pr.dir[row + size_t(r)] = d;
                    segs[size_t(r)] = solve::Segment{
                        float(cam.eye.x), float(cam.eye.y), float(cam.eye.z), 0.f, d.x, d.y, d.z,
                        INFINITY};
                }
        tracer.Intersect(segs, hits);
        for (size_t r = 0; r < segs.size(); ++r) {
            const solve::Hit& ht = hits[r];
            if (ht.geom_id == solve::kNoHit)
                continue;
            pr.first[row + r].triangle = ht.prim_id;
            const Vec3f& d = pr.dir[row + r];
            if (ht.ng_x * d.x + ht.ng_y * d.y + ht.ng_z * d.z >= 0) {
                pr.end[row + r] = RayEnd::Back;  // the back of a surface is black
                continue;
            }
            pr.first[row + r] = {ht.prim_id, ht.u, ht.v};
            pr.end[row + r] = RayEnd::Front;
        }
    });
    return pr;
}

}  // namespace

ReferenceImage RenderReferenceImage(const ReferenceMesh& mesh, const solve::Scene& scene,
                                    const ReferenceTracer& tracer, const ReferenceImageOptions& opt,
                                    const std::function<void(int, uint64_t)>& progress) {
    const PinholeRays rays(opt.camera);
    const int k = opt.strata;
    if (k < 1 || k > 16)
        UsageError("--aa {}: expected 1 to 16", k);
    const int w = opt.camera.width, h = opt.camera.height;
    const size_t per_pixel = size_t(k) * size_t(k);
    const size_t n_rays = size_t(w) * size_t(h) * per_pixel;
    const PrimaryRays pr = TracePrimaryRays(tracer, rays, k);
    const std::vector<RayEnd>& end = pr.end;
    const std::vector<Vec3f>& dir = pr.dir;

    // The front hits, in ray order, through the point estimator.
    std::vector<ReferencePoint> points;
    std::vector<uint32_t> point_of(n_rays, 0);
    for (size_t r = 0; r < n_rays; ++r)
        if (end[r] == RayEnd::Front) {
            point_of[r] = uint32_t(points.size());
            const PrimaryRays::FirstHit& f = pr.first[r];
            const double b[3] = {1.0 - double(f.u) - double(f.v), double(f.u), double(f.v)};
            points.push_back(PointAt(mesh, scene, f.triangle, b));
            points.back().stream = r;  // paths seeded by pixel and stratum
        }
    ReferenceImage img;
    img.width = w;
    img.height = h;
    img.points = points.size();
    if (!points.empty())
        img.stats = tracer.Estimate(points, opt.paths, progress);

    // Each pixel: the mean over its rays of B/pi, background or black; errors add in
    // quadrature (the rays' estimates are independent).
    img.rgb.assign(size_t(w) * size_t(h) * 3, 0.f);
    img.rule.assign(img.rgb.size(), 0.f);
    img.se.assign(img.rgb.size(), 0.f);
    img.coverage.assign(size_t(w) * size_t(h), 0.f);
    img.samples.assign(size_t(w) * size_t(h), 0);
    img.chart.assign(size_t(w) * size_t(h), -1);
    constexpr double kPi = std::numbers::pi;
    double se2_sum = 0, mean_sum = 0;
    for (size_t pix = 0; pix < size_t(w) * size_t(h); ++pix) {
        Vec3d sum{}, var{}, rule{};
        int covered = 0;
        for (size_t s = 0; s < per_pixel; ++s) {
            const size_t r = pix * per_pixel + s;
            if (end[r] == RayEnd::Miss) {
                sum += Vec3d(Background(scene, opt.background, dir[r]));
                rule += Vec3d(Background(scene, opt.background, dir[r]));
                continue;
            }
            ++covered;
            if (end[r] == RayEnd::Front) {
                const ReferencePoint& p = points[point_of[r]];
                sum += p.b / kPi;
                for (int c = 0; c < 3; ++c)
                    rule[c] += (kPi * p.emission[c] +
                                p.albedo[c] * std::max(0.0, Dot(p.normal, p.e[size_t(c)]))) /
                               kPi;
                img.samples[pix] += uint32_t(std::min<uint64_t>(p.samples, 0xFFFFFFFFu));
                for (int c = 0; c < 3; ++c)
                    var[c] += (p.b_se[c] / kPi) * (p.b_se[c] / kPi);
            }
        }
        if (end[pix * per_pixel] != RayEnd::Miss)
            img.chart[pix] = int32_t(mesh.chart[pr.first[pix * per_pixel].triangle]);
        const double inv = 1.0 / double(per_pixel);
        for (int c = 0; c < 3; ++c) {
            img.rgb[pix * 3 + size_t(c)] = float(sum[c] * inv);
            img.rule[pix * 3 + size_t(c)] = float(rule[c] * inv);
            img.se[pix * 3 + size_t(c)] = float(std::sqrt(var[c]) * inv);
        }
        img.coverage[pix] = float(covered * inv);
        if (size_t(covered) == per_pixel) {
            ++img.covered;
            const double se = (std::sqrt(var.x) + std::sqrt(var.y) + std::sqrt(var.z)) * inv / 3;
            se2_sum += se * se;
            mean_sum += (sum.x + sum.y + sum.z) * inv / 3;
        }
    }
    if (img.covered > 0 && mean_sum > 0)
        img.relative_noise =
            std::sqrt(se2_sum / double(img.covered)) / (mean_sum / double(img.covered));
    return img;
}

}  // namespace mebake::reference
