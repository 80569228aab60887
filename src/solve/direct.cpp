#include "solve/direct.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/check.h"
#include "solve/polygon_light.h"
#include "solve/rays.h"
#include "solve/visibility.h"

namespace mebake::solve {

namespace {

// A point of a polygon, by fan-triangle barycentrics: sample (a, b) in [0,1]^2 of
// triangle k. Used for deterministic stratified light samples.
Vec3d PolygonPoint(const std::vector<Vec3d>& v, size_t tri, double a, double b) {
    if (a + b > 1) a = 1 - a, b = 1 - b;
    return v[0] + (v[tri + 1] - v[0]) * a + (v[tri + 2] - v[0]) * b;
}

// Orthonormal frame with n as z (Duff et al. 2017).
void Frame(const Vec3f& n, Vec3f* t, Vec3f* b) {
    float sign = std::copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    *t = Vec3f(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    *b = Vec3f(c, sign + n.y * n.y * a, -n.y);
}

}  // namespace

std::vector<Vec3d> ClipToHalfSpace(std::span<const Vec3d> poly, const Vec3d& x, const Vec3d& n) {
    std::vector<Vec3d> out;
    const size_t m = poly.size();
    for (size_t k = 0; k < m; ++k) {
        const Vec3d& a = poly[k];
        const Vec3d& b = poly[(k + 1) % m];
        double da = Dot(a - x, n), db = Dot(b - x, n);
        if (da >= 0) out.push_back(a);
        if ((da >= 0) != (db >= 0)) out.push_back(a + (b - a) * (da / (da - db)));
    }
    return out;
}

DirectLight::DirectLight(const Scene& scene, const VisibilityScene& vis, float ray_offset,
                         float scene_size)
    : vis_(vis), sky_(scene.sky), offset_(ray_offset), far_(scene_size * 100) {
    const int per_tri = std::max(2, int(std::lround(std::sqrt(double(scene.solver.light_samples)))));
    for (const auto& pl : scene.lights) {
        Light l;
        l.vertices = pl.vertices;
        l.radiance = pl.radiance;
        l.two_sided = pl.two_sided;
        l.normal = PolygonNormal(pl.vertices);
        l.area = PolygonArea(pl.vertices);
        if (l.area <= 0) continue;
        Vec3d centre{};
        for (const auto& v : l.vertices) centre += v;
        centre = centre / double(l.vertices.size());
        // Classification points: vertices pulled 5% toward the centre, and the centre.
        for (const auto& v : l.vertices) l.classify.push_back(Vec3f(v + (centre - v) * 0.05));
        l.classify.push_back(Vec3f(centre));
        // Stratified samples: per fan triangle a per_tri x per_tri grid of cell centres.
        for (size_t t = 0; t + 2 < l.vertices.size(); ++t)
            for (int a = 0; a < per_tri; ++a)
                for (int b = 0; b < per_tri; ++b)
                    l.samples.push_back(Vec3f(PolygonPoint(l.vertices, t, (a + 0.5) / per_tri,
                                                           (b + 0.5) / per_tri)));
        lights_.push_back(std::move(l));
    }
    if (sky_.type != Sky::Type::None) {
        // Cosine-weighted directions: Shirley-Chiu concentric map of a k x k grid, lifted
        // to the hemisphere (Malley's method).
        int k = std::max(2, int(std::lround(std::sqrt(double(scene.solver.sky_directions)))));
        for (int a = 0; a < k; ++a) {
            for (int b = 0; b < k; ++b) {
                double x = 2 * (a + 0.5) / k - 1, y = 2 * (b + 0.5) / k - 1, r, phi;
                if (std::abs(x) > std::abs(y)) {
                    r = x;
                    phi = std::numbers::pi / 4 * (y / x);
                } else {
                    r = y;
                    phi = std::numbers::pi / 2 - std::numbers::pi / 4 * (x / y);
                }
                double dx = r * std::cos(phi), dy = r * std::sin(phi);
                double dz = std::sqrt(std::max(0.0, 1 - dx * dx - dy * dy));
                sky_dirs_.push_back(Vec3f(float(dx), float(dy), float(dz)));
            }
        }
    }
}

double DirectLight::EmittedPower() const {
    double p = 0;
    for (const auto& l : lights_) {
        double lum = (l.radiance.x + l.radiance.y + l.radiance.z) / 3;
        p += std::numbers::pi * lum * l.area * (l.two_sided ? 2 : 1);
    }
    return p;
}

void DirectLight::Evaluate(std::span<const ReceiverPoint> points, std::span<float> out) const {
    CHECK_EQ(out.size(), points.size() * 9);
    std::fill(out.begin(), out.end(), 0.f);
    SegmentBatch batch;
    std::vector<float> fraction(points.size());

    for (const auto& l : lights_) {
        // 1. Classify each point with a few rays (skip points the light cannot reach).
        batch.Clear();
        std::vector<uint8_t> faces(points.size(), 0);
        for (size_t p = 0; p < points.size(); ++p) {
            const auto& rp = points[p];
            double side = Dot(Vec3d(rp.position) - l.vertices[0], l.normal);
            bool front = side > 0 || (l.two_sided && side < 0);
            // Some of the light must be above the receiver's horizon.
            bool above = false;
            for (const auto& v : l.vertices) above |= Dot(v - Vec3d(rp.position), Vec3d(rp.normal)) > 0;
            faces[p] = front && above;
            if (!faces[p]) continue;
            Vec3f o = rp.vis_point + rp.normal * offset_;
            for (const auto& c : l.classify) batch.AddSegment(o, c);
        }
        batch.Trace(vis_);
        size_t at = 0;
        std::vector<size_t> penumbra;
        for (size_t p = 0; p < points.size(); ++p) {
            fraction[p] = 0;
            if (!faces[p]) continue;
            size_t vis = 0;
            for (size_t k = 0; k < l.classify.size(); ++k) vis += batch.occluded[at++] ? 0 : 1;
            if (vis == l.classify.size()) fraction[p] = 1;
            else if (vis > 0) penumbra.push_back(p);
            else fraction[p] = 0;
        }
        // 2. Penumbra points: the visible fraction of stratified samples.
        batch.Clear();
        for (size_t p : penumbra) {
            Vec3f o = points[p].vis_point + points[p].normal * offset_;
            for (const auto& s : l.samples) batch.AddSegment(o, s);
        }
        batch.Trace(vis_);
        at = 0;
        for (size_t p : penumbra) {
            size_t vis = 0;
            for (size_t k = 0; k < l.samples.size(); ++k) vis += batch.occluded[at++] ? 0 : 1;
            fraction[p] = float(vis) / float(l.samples.size());
        }
        // 3. Closed form, clipped to the receiver's upper hemisphere.
        for (size_t p = 0; p < points.size(); ++p) {
            if (fraction[p] <= 0) continue;
            const Vec3d x(points[p].position), n(points[p].normal);
            auto clipped = ClipToHalfSpace(l.vertices, x, n);
            if (clipped.size() < 3) continue;
            Vec3d e = VectorIrradiance(clipped, 1.0, x,
                                       l.two_sided ? Emission::kBoth : Emission::kFront) *
                      double(fraction[p]);
            for (int c = 0; c < 3; ++c)
                for (int k = 0; k < 3; ++k) out[p * 9 + size_t(3 * c + k)] += float(l.radiance[c] * e[k]);
        }
    }

    if (sky_.type != Sky::Type::None) {
        batch.Clear();
        const Vec3f up(sky_.up);
        std::vector<Vec3f> dirs;
        dirs.reserve(points.size() * sky_dirs_.size());
        for (const auto& rp : points) {
            Vec3f t, b;
            Frame(rp.normal, &t, &b);
            Vec3f o = rp.vis_point + rp.normal * offset_;
            for (const auto& d : sky_dirs_) {
                Vec3f w = t * d.x + b * d.y + rp.normal * d.z;
                dirs.push_back(w);
                if (Dot(w, up) > 0) batch.Add(o, w, far_);
            }
        }
        batch.Trace(vis_);
        // Estimator of E = integral of L(w) V w dw with pdf cos/pi: sum L w pi / (cos N).
        const float scale = float(std::numbers::pi) / float(sky_dirs_.size());
        size_t at = 0, di = 0;
        for (size_t p = 0; p < points.size(); ++p) {
            for (size_t k = 0; k < sky_dirs_.size(); ++k, ++di) {
                const Vec3f& w = dirs[di];
                float cos_up = Dot(w, up);
                if (cos_up <= 0) continue;
                if (batch.occluded[at++]) continue;
                float cos_n = std::max(sky_dirs_[k].z, 1e-3f);
                double gain = sky_.type == Sky::Type::Overcast ? (1 + 2 * cos_up) / 3.0 : 1.0;
                for (int c = 0; c < 3; ++c) {
                    float l = float(sky_.radiance[c] * gain) * scale / cos_n;
                    for (int e = 0; e < 3; ++e) out[p * 9 + size_t(3 * c + e)] += l * w[e];
                }
            }
        }
    }
}

}  // namespace mebake::solve
