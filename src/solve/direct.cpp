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

// The point with barycentrics (a, b) in fan triangle `tri` of a polygon.
Vec3d PolygonPoint(const std::vector<Vec3d>& v, size_t tri, double a, double b) {
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

DirectLight::DirectLight(const Scene& scene, const SolverSettings& settings,
                         const VisibilityScene& vis, float ray_offset, float scene_size)
    : vis_(vis), sky_(scene.sky), offset_(ray_offset), far_(scene_size * 100) {
    const int per_tri = std::max(2, int(std::lround(std::sqrt(double(settings.light_samples)))));
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
        // Classification points: vertices pulled 1% toward the centre, and the centre.
        for (const auto& v : l.vertices) l.classify.push_back(Vec3f(v + (centre - v) * 0.01));
        l.classify.push_back(Vec3f(centre));
        // Cells: each fan triangle cut into per_tri^2 congruent triangles.
        for (size_t t = 0; t + 2 < l.vertices.size(); ++t) {
            const double k = per_tri;
            auto at = [&](int a, int b) { return PolygonPoint(l.vertices, t, a / k, b / k); };
            for (int a = 0; a < per_tri; ++a) {
                for (int b = 0; a + b < per_tri; ++b) {
                    l.cells.push_back({at(a, b), at(a + 1, b), at(a, b + 1)});
                    if (a + b + 2 <= per_tri) l.cells.push_back({at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)});
                }
            }
        }
        // One sample per cell at a fixed pseudo-random point (an R2 low-discrepancy
        // sequence): a shadow edge parallel to the cell rows then cuts samples at varied
        // offsets, so the misclassified parts cancel instead of adding up along the edge.
        for (size_t c = 0; c < l.cells.size(); ++c) {
            double a = std::fmod(0.5 + 0.7548776662466927 * double(c + 1), 1.0);
            double b = std::fmod(0.5 + 0.5698402909980532 * double(c + 1), 1.0);
            if (a + b > 1) a = 1 - a, b = 1 - b;
            const auto& t = l.cells[c];
            l.samples.push_back(Vec3f(t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b));
        }
        lights_.push_back(std::move(l));
    }
    if (sky_.type != Sky::Type::None) {
        // Cosine-weighted directions: Shirley-Chiu concentric map of a k x k grid, lifted
        // to the hemisphere (Malley's method).
        int k = std::max(2, int(std::lround(std::sqrt(double(settings.sky_directions)))));
        for (int a = 0; a < k; ++a) {
            for (int b = 0; b < k; ++b) {
                double x = 2 * (a + 0.5) / k - 1, y = 2 * (b + 0.5) / k - 1, r, phi;
                if (x == 0 && y == 0) {
                    r = 0;
                    phi = 0;
                } else if (std::abs(x) > std::abs(y)) {
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

void DirectLight::Evaluate(std::span<const ReceiverPoint> points, std::span<float> out,
                           int parts) const {
    CHECK_EQ(out.size(), points.size() * 9);
    std::fill(out.begin(), out.end(), 0.f);
    SegmentBatch batch;
    std::vector<float> fraction(points.size());

    for (const auto& l : lights_) {
        if (!(parts & kLights)) break;
        // 1. Classify each point with a few rays (skip points the light cannot reach).
        batch.Clear();
        std::vector<uint8_t> faces(points.size(), 0);
        for (size_t p = 0; p < points.size(); ++p) {
            const auto& rp = points[p];
            // E does not involve the receiver's normal (that is what keeps it smooth on
            // noisy scans): what lies below the surface is removed by visibility alone.
            double side = Dot(Vec3d(rp.position) - l.vertices[0], l.normal);
            bool above = Dot(rp.horizon, rp.horizon) == 0;
            for (const auto& v : l.vertices)
                above |= Dot(v - Vec3d(rp.position), Vec3d(rp.horizon)) > 0;
            faces[p] = (side > 0 || (l.two_sided && side < 0)) && above;
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
        // 2. Penumbra points: the closed form of every cell whose centroid is visible.
        batch.Clear();
        for (size_t p : penumbra) {
            Vec3f o = points[p].vis_point + points[p].normal * offset_;
            for (const auto& s : l.samples) batch.AddSegment(o, s);
        }
        batch.Trace(vis_);
        const Emission emission = l.two_sided ? Emission::kBoth : Emission::kFront;
        auto add = [&](size_t p, const Vec3d& e) {
            for (int c = 0; c < 3; ++c)
                for (int k = 0; k < 3; ++k) out[p * 9 + size_t(3 * c + k)] += float(l.radiance[c] * e[k]);
        };
        // The closed form of a polygon above the point's horizon.
        auto above = [&](std::span<const Vec3d> poly, size_t p) {
            const Vec3d x(points[p].position), h(points[p].horizon);
            if (Dot(h, h) == 0) return VectorIrradiance(poly, 1.0, x, emission);
            auto clipped = ClipToHalfSpace(poly, x, h);
            return clipped.size() >= 3 ? VectorIrradiance(clipped, 1.0, x, emission) : Vec3d{};
        };
        at = 0;
        for (size_t p : penumbra) {
            Vec3d e{};
            for (size_t k = 0; k < l.cells.size(); ++k)
                if (!batch.occluded[at++]) e += above(l.cells[k], p);
            add(p, e);
        }
        // 3. Fully lit points: the closed form.
        for (size_t p = 0; p < points.size(); ++p)
            if (fraction[p] > 0) add(p, above(l.vertices, p));
    }

    if (sky_.type != Sky::Type::None && (parts & kSky)) {
        // Fixed world-frame directions about the sky's up axis (cosine-weighted), so E
        // changes with position only where visibility does.
        batch.Clear();
        const Vec3f up(sky_.up);
        Vec3f t, b;
        Frame(up, &t, &b);
        std::vector<Vec3f> dirs(sky_dirs_.size());
        for (size_t k = 0; k < sky_dirs_.size(); ++k)
            dirs[k] = t * sky_dirs_[k].x + b * sky_dirs_[k].y + up * sky_dirs_[k].z;
        for (const auto& rp : points) {
            const Vec3f o = rp.vis_point + rp.normal * offset_;
            for (const auto& w : dirs) {
                // Below the horizon: no ray, counted as blocked (tfar 0 never hits).
                bool below = Dot(w, rp.horizon) < 0;
                batch.Add(o, w, below ? -1.f : far_);
            }
        }
        batch.Trace(vis_);
        for (size_t k = 0; k < batch.size(); ++k)
            if (batch.segments[k].tfar < 0) batch.occluded[k] = 1;
        // Estimator of E = integral of L(w) V w dw with pdf cos/pi: sum L w pi / (cos N).
        const float scale = float(std::numbers::pi) / float(sky_dirs_.size());
        size_t at = 0;
        for (size_t p = 0; p < points.size(); ++p) {
            for (size_t k = 0; k < dirs.size(); ++k) {
                if (batch.occluded[at++]) continue;
                const Vec3f& w = dirs[k];
                const float cos_up = std::max(sky_dirs_[k].z, 1e-3f);
                const double gain = sky_.type == Sky::Type::Overcast ? (1 + 2 * cos_up) / 3.0 : 1.0;
                for (int c = 0; c < 3; ++c) {
                    const float l = float(sky_.radiance[c] * gain) * scale / cos_up;
                    for (int e = 0; e < 3; ++e) out[p * 9 + size_t(3 * c + e)] += l * w[e];
                }
            }
        }
    }
}

}  // namespace mebake::solve
