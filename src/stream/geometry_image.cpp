#include "stream/geometry_image.h"

#include <algorithm>
#include <cmath>

#include "core/check.h"

namespace mebake::stream {

void GeometryImage::BuildPyramid() {
    CHECK(!levels.empty());
    for (int l = finest_level() - 1; l >= 0; --l) {
        const auto& fine = levels[size_t(l) + 1];
        auto& coarse = levels[size_t(l)];
        const uint32_t n = 1u << l, fn = n * 2;
        coarse.assign(size_t(n) * n, GeometryTexel{});
        for (uint32_t j = 0; j < n; ++j) {
            for (uint32_t i = 0; i < n; ++i) {
                const GeometryTexel* kids[4] = {
                    &fine[size_t(2 * j) * fn + 2 * i], &fine[size_t(2 * j) * fn + 2 * i + 1],
                    &fine[size_t(2 * j + 1) * fn + 2 * i], &fine[size_t(2 * j + 1) * fn + 2 * i + 1]};
                GeometryTexel& t = coarse[size_t(j) * n + i];
                double area = 0, cover = 0;
                Vec3d pos{}, nrm{}, col{}, vis{};
                int col_n = 0;
                const GeometryTexel* biggest = kids[0];
                for (const auto* k : kids) {
                    area += k->area;
                    cover += k->coverage;
                    if (k->area > biggest->area) biggest = k;
                }
                // Real texels weigh by area; an all-virtual block averages evenly so the
                // extrapolated surface stays continuous.
                for (const auto* k : kids) {
                    double w = area > 0 ? k->area / area : 0.25;
                    pos += Vec3d(k->position) * w;
                    nrm += Vec3d(k->normal) * w;
                    vis += Vec3d(k->vis_point) * w;
                    if (k->color.x >= 0) {
                        col += Vec3d(k->color) * w;
                        ++col_n;
                    }
                }
                t.position = Vec3f(pos);
                Vec3d nn = Normalize(nrm);
                t.normal = Length(nrm) > 0 ? Vec3f(nn) : biggest->normal;
                t.area = float(area);
                t.coverage = float(cover / 4);
                t.material = biggest->material;
                t.color = col_n ? Vec3f(col * (area > 0 ? 1.0 : 4.0 / col_n)) : Vec3f(-1, -1, -1);
                // The visibility point must be a real surface point: the child's nearest
                // to the averaged one (an average of points of a curved surface is not on it).
                const GeometryTexel* best = biggest;
                double best_d = 1e300;
                for (const auto* k : kids) {
                    if (area > 0 && k->area <= 0) continue;
                    double d = Length(Vec3d(k->vis_point) - vis);
                    if (d < best_d) best_d = d, best = k;
                }
                t.vis_point = best->vis_point;
                float r = 0;
                for (const auto* k : kids)
                    r = std::max(r, Length(k->position - t.position) + k->radius);
                t.radius = r;
            }
        }
    }
}

SurfaceSample SampleBilinear(const GeometryImage& img, int level, float u, float v) {
    // Texel centres are the samples; outside the outermost centres the image is
    // extrapolated linearly (clamping would move border points by half a texel).
    level = std::min(std::max(level, 1), img.finest_level());
    const int nn = 1 << level;
    const float x = u * float(nn) - 0.5f, y = v * float(nn) - 0.5f;
    const int i0 = nn > 1 ? std::clamp(int(std::floor(x)), 0, nn - 2) : 0;
    const int j0 = nn > 1 ? std::clamp(int(std::floor(y)), 0, nn - 2) : 0;
    const int i1 = std::min(i0 + 1, nn - 1), j1 = std::min(j0 + 1, nn - 1);
    const float fx = nn > 1 ? x - float(i0) : 0.f, fy = nn > 1 ? y - float(j0) : 0.f;
    const GeometryTexel* t[4] = {&img.At(level, uint32_t(i0), uint32_t(j0)),
                                 &img.At(level, uint32_t(i1), uint32_t(j0)),
                                 &img.At(level, uint32_t(i0), uint32_t(j1)),
                                 &img.At(level, uint32_t(i1), uint32_t(j1))};
    const float w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    SurfaceSample s{};
    Vec3f nrm{};
    float col_w = 0;
    int best = 0;
    // The nearest texel decides discrete attributes and the visibility point.
    const float dx = std::clamp(x, 0.f, float(nn - 1)) - float(i0);
    const float dy = std::clamp(y, 0.f, float(nn - 1)) - float(j0);
    best = (dx >= 0.5f ? 1 : 0) + (dy >= 0.5f ? 2 : 0);
    for (int k = 0; k < 4; ++k) {
        s.position += t[k]->position * w[k];
        nrm += t[k]->normal * w[k];
        s.coverage += t[k]->coverage * w[k];
        if (t[k]->color.x >= 0) {
            s.color += t[k]->color * w[k];
            col_w += w[k];
        }
    }
    s.coverage = std::clamp(s.coverage, 0.f, 1.f);
    s.normal = Length(nrm) > 0 ? Normalize(nrm) : t[best]->normal;
    s.color = col_w > 0 ? Vec3f(std::clamp(s.color.x / col_w, 0.f, 1.f),
                                std::clamp(s.color.y / col_w, 0.f, 1.f),
                                std::clamp(s.color.z / col_w, 0.f, 1.f))
                        : Vec3f(-1, -1, -1);
    s.material = t[best]->material;
    // Visibility is taken at the sample itself where the surface is real, else at the
    // nearest texel's real point (the seed's x' rule).
    s.vis_point = t[best]->coverage >= 0.999f ? s.position : t[best]->vis_point;
    return s;
}

}  // namespace mebake::stream
