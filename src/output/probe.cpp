#include "output/probe.h"

#include "core/check.h"
#include "core/error.h"
#include "solve/shading.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace mebake::output {

std::vector<ProbeValue> ProbeSolution(const BakeView& view, std::span<const ProbeSite> sites) {
    std::vector<ProbeValue> out(sites.size());
    for (size_t i = 0; i < sites.size(); ++i) {
        const ProbeSite& s = sites[i];
        if (s.chart >= view.chart_count())
            InputError({"probe"}, "point {}: chart {} does not exist ({} charts)", i, s.chart,
                       view.chart_count());
        for (int k = 0; k < 3; ++k)
            if (!std::isfinite(s.barycentric[k]))
                InputError({"probe"}, "point {}: barycentrics are not finite", i);
    }
    // Sites grouped by chart, each chart's tile read once.
    std::vector<uint32_t> order(sites.size());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(),
                     [&](uint32_t a, uint32_t b) { return sites[a].chart < sites[b].chart; });
    std::vector<uint32_t> charts;
    for (uint32_t i : order)
        if (charts.empty() || charts.back() != sites[i].chart)
            charts.push_back(sites[i].chart);
    std::vector<size_t> first(view.chart_count() + 1, 0);
    for (const ProbeSite& s : sites)
        ++first[s.chart + 1];
    for (size_t c = 0; c < view.chart_count(); ++c)
        first[c + 1] += first[c];
    ForEachTile(
        view, charts, stream::TileParts::Mesh,
        [&](uint32_t c, const stream::ChartTile& tile) {
            ChartShader shader(tile, view.solution.fields[c], view.solution.radiosity, view.scene,
                               view.TilePath(c), view.Seams(c));
            for (size_t k = first[c]; k < first[c + 1]; ++k) {
                const uint32_t i = order[k];
                const ProbeSite& s = sites[i];
                if (s.local_triangle >= tile.triangles.size())
                    InputError({view.TilePath(c)}, "point {}: triangle {} does not exist ({})", i,
                               s.local_triangle, tile.triangles.size());
                const ShadingPoint p = shader.AtTriangle(s.local_triangle, s.barycentric[0],
                                                         s.barycentric[1], s.barycentric[2]);
                ProbeValue& v = out[i];
                v.b = shader.Radiosity(p);
                shader.Irradiance(p.uv, v.e);
                v.uv = p.uv;
                v.normal = p.normal;
                const auto& f = tile.triangles[s.local_triangle];
                v.face_normal = Normalize(Cross(tile.position[f[1]] - tile.position[f[0]],
                                                tile.position[f[2]] - tile.position[f[0]]));
                v.albedo = p.albedo;
                v.emission = p.material->emission;
            }
            return 0;
        },
        [](uint32_t, const stream::ChartTile&, int) {});
    return out;
}

Vec3d DisplayRule(const ProbeValue& v, const Vec3d e[3]) {
    float val[9];
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k)
            val[3 * c + k] = float(e[c][k]);
    solve::Material m;
    m.emission = v.emission;
    return Vec3d(solve::ShadeRadiosity(val, false, v.normal, v.albedo, m));
}

ProbeError CompareRadiosity(std::span<const Vec3d> reference, std::span<const Vec3d> reference_se,
                            std::span<const Vec3d> bake) {
    CHECK_EQ(reference.size(), bake.size());
    CHECK_EQ(reference.size(), reference_se.size());
    ProbeError r;
    r.points = reference.size();
    if (reference.empty())
        return r;
    double ref2 = 0, err2 = 0, se2 = 0, max_err = 0, sum_b = 0, sum_r = 0;
    for (size_t i = 0; i < reference.size(); ++i) {
        const Vec3d d = bake[i] - reference[i];
        ref2 += Dot(reference[i], reference[i]);
        err2 += Dot(d, d);
        se2 += Dot(reference_se[i], reference_se[i]);
        max_err = std::max(max_err, Length(d));
        sum_b += Length(bake[i]);
        sum_r += Length(reference[i]);
    }
    const double n = double(reference.size());
    const double level = std::sqrt(ref2 / n);
    r.mean_bake = sum_b / n;
    r.mean_reference = sum_r / n;
    if (!(level > 0))
        return r;
    r.relative_rms = std::sqrt(err2 / n) / level;
    r.relative_max = max_err / level;
    r.noise_rms = std::sqrt(se2 / n) / level;
    r.corrected_rms =
        std::sqrt(std::max(0.0, r.relative_rms * r.relative_rms - r.noise_rms * r.noise_rms));
    std::vector<double> rel(reference.size());
    for (size_t i = 0; i < reference.size(); ++i)
        rel[i] = Length(bake[i] - reference[i]) / std::max(Length(reference[i]), 1e-3 * level);
    std::nth_element(rel.begin(), rel.begin() + ptrdiff_t(rel.size() / 2), rel.end());
    r.median_relative = rel[rel.size() / 2];
    return r;
}

}  // namespace mebake::output
