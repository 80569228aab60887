#include "stream/geometry_image.h"

#include "core/check.h"

#include <algorithm>
#include <cmath>

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
                const GeometryTexel* kids[4] = {&fine[size_t(2 * j) * fn + 2 * i],
                                                &fine[size_t(2 * j) * fn + 2 * i + 1],
                                                &fine[size_t(2 * j + 1) * fn + 2 * i],
                                                &fine[size_t(2 * j + 1) * fn + 2 * i + 1]};
                GeometryTexel& t = coarse[size_t(j) * n + i];
                double area = 0, cover = 0;
                Vec3d pos{}, nrm{}, col{}, vis{};
                int col_n = 0;
                const GeometryTexel* biggest = kids[0];
                for (const auto* k : kids) {
                    area += k->area;
                    cover += k->coverage;
                    if (k->area > biggest->area)
                        biggest = k;
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
                    if (area > 0 && k->area <= 0)
                        continue;
                    double d = Length(Vec3d(k->vis_point) - vis);
                    if (d < best_d)
                        best_d = d, best = k;
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
    return SampleBilinearOf(img, level, u, v);
}

}  // namespace mebake::stream
