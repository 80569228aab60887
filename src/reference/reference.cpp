#include "reference/reference.h"

#include "core/check.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "solve/visibility.h"
#include "stream/tile.h"
#include "stream/trimesh.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>

namespace mebake::reference {

namespace {

constexpr double kPi = std::numbers::pi;

// SplitMix64 (Steele, Lea, Flood 2014): a counter-based stream per (seed, point, sample).
struct Rng {
    uint64_t state;
    Rng(uint64_t seed, uint64_t point, uint64_t sample) {
        state = Mix(seed ^ Mix(point * 0x9E3779B97F4A7C15ull + 1) ^
                    Mix(sample * 0xC2B2AE3D27D4EB4Full + 7));
    }
    static uint64_t Mix(uint64_t z) {
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    uint64_t Next() { return Mix(state += 0x9E3779B97F4A7C15ull); }
    double Uniform() { return double(Next() >> 11) * 0x1.0p-53; }  // [0, 1)
};

// The sRGB transfer function (IEC 61966-2-1) and the material's albedo rule of
// docs/scene-format.md: vertex colours, decoded and scaled, replace Kd, capped at 0.99.
float SrgbDecode(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}
Vec3d Albedo(const solve::Material& m, const Vec3f& color) {
    Vec3f a = m.albedo;
    if (m.use_vertex_colors && color.x >= 0)
        for (int c = 0; c < 3; ++c)
            a[c] = std::min(0.99f, SrgbDecode(color[c]) * m.color_factor);
    return Vec3d(a);
}

// Orthonormal frame around unit n (Duff et al. 2017).
void Frame(const Vec3d& n, Vec3d& t, Vec3d& b) {
    const double s = n.z >= 0 ? 1.0 : -1.0;
    const double a = -1.0 / (s + n.z);
    const double c = n.x * n.y * a;
    t = Vec3d(1 + s * n.x * n.x * a, s * c, -s * n.x);
    b = Vec3d(c, s + n.y * n.y * a, -n.y);
}

Vec3d CosineSample(const Vec3d& n, double u1, double u2) {
    Vec3d t, b;
    Frame(n, t, b);
    const double r = std::sqrt(u1), phi = 2 * kPi * u2;
    return t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * std::sqrt(std::max(0.0, 1 - u1));
}

Vec3d UniformHemisphere(const Vec3d& n, double u1, double u2) {
    Vec3d t, b;
    Frame(n, t, b);
    const double z = u1, r = std::sqrt(std::max(0.0, 1 - z * z)), phi = 2 * kPi * u2;
    return t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * z;
}

double MaxOf(const Vec3d& v) {
    return std::max(v.x, std::max(v.y, v.z));
}
Vec3d Mul(const Vec3d& a, const Vec3d& b) {
    return {a.x * b.x, a.y * b.y, a.z * b.z};
}

// An emitter sampled by area: a polygon light (rejection-sampled in its plane) or an
// emissive triangle of the mesh.
struct Emitter {
    Vec3d radiance;
    Vec3d normal;  // front
    bool two_sided = false;
    double area = 0;
    // Polygon: origin, in-plane axes, 2D outline and its bounding box.
    Vec3d origin, ax, ay;
    std::vector<Vec2d> outline;
    Vec2d lo, hi;
    // Triangle.
    bool triangle = false;
    Vec3d p0, p1, p2;

    bool Inside(const Vec2d& q) const {  // even-odd rule
        bool in = false;
        for (size_t i = 0, j = outline.size() - 1; i < outline.size(); j = i++) {
            const Vec2d& a = outline[i];
            const Vec2d& b = outline[j];
            if ((a.y > q.y) != (b.y > q.y) && q.x < (b.x - a.x) * (q.y - a.y) / (b.y - a.y) + a.x)
                in = !in;
        }
        return in;
    }
    // A uniform point on the emitter; false if rejection sampling gave up (a sliver polygon).
    bool Sample(Rng& rng, Vec3d& y) const {
        if (triangle) {
            const double su = std::sqrt(rng.Uniform()), v = rng.Uniform();
            y = p0 * (1 - su) + p1 * (su * (1 - v)) + p2 * (su * v);
            return true;
        }
        for (int k = 0; k < 256; ++k) {
            const Vec2d q(lo.x + (hi.x - lo.x) * rng.Uniform(),
                          lo.y + (hi.y - lo.y) * rng.Uniform());
            if (Inside(q)) {
                y = origin + ax * q.x + ay * q.y;
                return true;
            }
        }
        return false;
    }
};

Emitter MakePolygonEmitter(const solve::PolygonLight& pl) {
    Emitter e;
    e.radiance = pl.radiance;
    e.two_sided = pl.two_sided;
    const auto& v = pl.vertices;
    Vec3d n{};
    for (size_t i = 0; i < v.size(); ++i) {  // Newell's method
        const Vec3d& a = v[i];
        const Vec3d& b = v[(i + 1) % v.size()];
        n += Vec3d((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
    }
    e.normal = Normalize(n);
    if (!(Dot(e.normal, e.normal) > 0))
        return e;  // degenerate: area 0, never sampled
    e.origin = v[0];
    Vec3d t, b;
    Frame(e.normal, t, b);
    e.ax = t;
    e.ay = b;
    e.lo = Vec2d(1e300, 1e300);
    e.hi = Vec2d(-1e300, -1e300);
    double area2 = 0;
    for (const Vec3d& p : v) {
        const Vec2d q(Dot(p - e.origin, t), Dot(p - e.origin, b));
        e.outline.push_back(q);
        e.lo = Vec2d(std::min(e.lo.x, q.x), std::min(e.lo.y, q.y));
        e.hi = Vec2d(std::max(e.hi.x, q.x), std::max(e.hi.y, q.y));
    }
    for (size_t i = 0; i < e.outline.size(); ++i)
        area2 += Cross(e.outline[i], e.outline[(i + 1) % e.outline.size()]);
    e.area = std::abs(area2) / 2;
    return e;
}

}  // namespace

ReferenceMesh LoadReferenceMesh(const std::string& dir, const stream::Manifest& manifest) {
    ReferenceMesh mesh;
    bool any_color = false;
    for (uint32_t c = 0; c < manifest.charts.size(); ++c) {
        const std::string path = stream::TilePath(dir, c);
        const stream::ChartTile tile = stream::ReadTile(path, stream::TileParts::Mesh);
        const size_t n = tile.position.size();
        if (tile.normal.size() != n || tile.uv.size() != n ||
            tile.material.size() != tile.triangles.size() ||
            (!tile.color.empty() && tile.color.size() != n))
            CorruptError({path}, "tile arrays disagree in size");
        const uint32_t base = uint32_t(mesh.position.size());
        if (uint64_t(base) + n > 0xFFFFFFF0ull)
            InputError({path}, "mesh too large for a reference");
        mesh.position.insert(mesh.position.end(), tile.position.begin(), tile.position.end());
        mesh.normal.insert(mesh.normal.end(), tile.normal.begin(), tile.normal.end());
        mesh.uv.insert(mesh.uv.end(), tile.uv.begin(), tile.uv.end());
        if (tile.vertex_id.size() == n)
            mesh.vertex_id.insert(mesh.vertex_id.end(), tile.vertex_id.begin(),
                                  tile.vertex_id.end());
        else
            mesh.vertex_id.insert(mesh.vertex_id.end(), n, stream::kNoId);
        if (!tile.color.empty()) {
            if (!any_color)
                mesh.color.assign(base, Vec3f(-1, -1, -1));
            any_color = true;
            mesh.color.insert(mesh.color.end(), tile.color.begin(), tile.color.end());
        } else if (any_color) {
            mesh.color.insert(mesh.color.end(), n, Vec3f(-1, -1, -1));
        }
        for (size_t t = 0; t < tile.triangles.size(); ++t) {
            std::array<uint32_t, 3> f = tile.triangles[t];
            for (uint32_t& i : f) {
                if (i >= n)
                    CorruptError({path}, "triangle {} has vertex {} of {}", t, i, n);
                i += base;
            }
            mesh.triangles.push_back(f);
            mesh.material.push_back(tile.material[t]);
            mesh.chart.push_back(c);
            mesh.local_triangle.push_back(uint32_t(t));
            mesh.face_id.push_back(tile.face_id.size() == tile.triangles.size() ? tile.face_id[t]
                                                                                : stream::kNoId);
        }
    }
    return mesh;
}

namespace {

void CheckMaterials(const ReferenceMesh& mesh, const solve::Scene& scene) {
    for (size_t t = 0; t < mesh.material.size(); ++t) {
        const uint32_t packed = mesh.material[t];
        if ((packed >> 16) >= scene.per_input.size() ||
            (packed & 0xFFFF) >= scene.per_input[packed >> 16].size())
            InputError({"scene"}, "triangle {} has material {}:{} which the scene does not have", t,
                       packed >> 16, packed & 0xFFFF);
    }
}

struct Surface {  // a point of a triangle as shading sees it
    Vec3d position, normal, geometric_normal, albedo;
    const solve::Material* material = nullptr;
    Vec2f uv;
};

Surface SurfaceAt(const ReferenceMesh& mesh, const solve::Scene& scene, uint32_t t, const double b[3]) {
    const auto& f = mesh.triangles[t];
    const Vec3d p0(mesh.position[f[0]]), p1(mesh.position[f[1]]), p2(mesh.position[f[2]]);
    Surface s;
    s.position = p0 * b[0] + p1 * b[1] + p2 * b[2];
    s.geometric_normal = Normalize(Cross(p1 - p0, p2 - p0));
    Vec3d n{}, col{};
    Vec2f uv{};
    bool colored = !mesh.color.empty();
    for (int k = 0; k < 3; ++k) {
        n += Vec3d(mesh.normal[f[k]]) * b[k];
        uv += mesh.uv[f[k]] * float(b[k]);
        if (colored) {
            if (mesh.color[f[k]].x < 0)
                colored = false;
            col += Vec3d(mesh.color[f[k]]) * b[k];
        }
    }
    s.normal = Normalize(n);
    // A shading normal on the wrong side of its triangle (or none) falls back to the plane's.
    if (!(Dot(s.normal, s.geometric_normal) > 0))
        s.normal = s.geometric_normal;
    s.uv = uv;
    s.material = &scene.MaterialOf(mesh.material[t]);
    s.albedo = Albedo(*s.material, colored ? Vec3f(col) : Vec3f(-1, -1, -1));
    return s;
}

}  // namespace

ReferencePoint PointAt(const ReferenceMesh& mesh, const solve::Scene& scene, uint32_t t,
                       const double b[3]) {
    const Surface s = SurfaceAt(mesh, scene, t, b);
    ReferencePoint p;
    p.triangle = t;
    p.chart = mesh.chart[t];
    p.local_triangle = mesh.local_triangle[t];
    p.face_id = t < mesh.face_id.size() ? mesh.face_id[t] : stream::kNoId;
    for (int k = 0; k < 3; ++k) {
        const uint32_t vk = mesh.triangles[t][size_t(k)];
        p.vertex_ids[size_t(k)] = vk < mesh.vertex_id.size() ? mesh.vertex_id[vk] : stream::kNoId;
    }
    p.barycentric = Vec3f(float(b[0]), float(b[1]), float(b[2]));
    p.uv = s.uv;
    p.position = s.position;
    p.normal = s.normal;
    p.geometric_normal = s.geometric_normal;
    p.albedo = s.albedo;
    p.emission = Vec3d(s.material->emission);
    return p;
}

std::vector<ReferencePoint> ChooseReferencePoints(const ReferenceMesh& mesh, const solve::Scene& scene,
                                                  int n, uint64_t seed) {
    if (n < 1)
        UsageError("--points must be at least 1");
    CheckMaterials(mesh, scene);
    std::vector<double> cdf(mesh.triangles.size());
    double total = 0;
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& f = mesh.triangles[t];
        const Vec3d p0(mesh.position[f[0]]), p1(mesh.position[f[1]]), p2(mesh.position[f[2]]);
        const double a = Length(Cross(p1 - p0, p2 - p0)) / 2;
        total += std::isfinite(a) ? a : 0;
        cdf[t] = total;
    }
    if (!(total > 0))
        InputError({"mesh"}, "the mesh has no area to place reference points on");
    std::vector<ReferencePoint> points(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
        Rng rng(seed, uint64_t(i), ~uint64_t(0));
        const double x = rng.Uniform() * total;
        size_t t = size_t(std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin());
        t = std::min(t, cdf.size() - 1);
        while (t > 0 && cdf[t] == cdf[t - 1])
            --t;  // never a zero-area triangle
        const double su = std::sqrt(rng.Uniform()), v = rng.Uniform();
        const double b[3] = {1 - su, su * (1 - v), su * v};
        points[size_t(i)] = PointAt(mesh, scene, uint32_t(t), b);
    }
    return points;
}

struct ReferenceTracer::Impl {
    const ReferenceMesh& mesh;
    const solve::Scene& scene;
    solve::VisibilityScene vis;
    std::vector<Emitter> emitters;
    std::vector<double> emitter_cdf;  // by power
    double eps = 0;                   // ray origin offset along the geometric normal
    mutable std::atomic<uint64_t> rays{0};

    Impl(const ReferenceMesh& m, const solve::Scene& s)
        : mesh(m),
          scene(s),
          vis(solve::VisibilityOptions{.compact = false,
                                .robust = true,
                                .quality = solve::BuildQuality::kHigh,
                                .method = solve::TraceMethod::kSingle,
                                .coherent = false}) {
        CheckMaterials(mesh, scene);
        std::vector<float> pos;
        pos.reserve(mesh.position.size() * 3);
        Vec3d lo(1e300, 1e300, 1e300), hi(-1e300, -1e300, -1e300);
        for (const Vec3f& p : mesh.position) {
            pos.insert(pos.end(), {p.x, p.y, p.z});
            lo = Min(lo, Vec3d(p));
            hi = Max(hi, Vec3d(p));
        }
        std::vector<uint32_t> idx;
        idx.reserve(mesh.triangles.size() * 3);
        for (const auto& f : mesh.triangles)
            idx.insert(idx.end(), f.begin(), f.end());
        vis.AddTriangles(pos, idx, "reference mesh");
        vis.Commit();
        eps = mesh.position.empty() ? 1e-6 : 1e-5 * Length(hi - lo) + 1e-30;

        for (const solve::PolygonLight& pl : scene.lights) {
            Emitter e = MakePolygonEmitter(pl);
            if (e.area > 0 && MaxOf(e.radiance) > 0)
                emitters.push_back(std::move(e));
        }
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const solve::Material& mat = scene.MaterialOf(mesh.material[t]);
            if (!mat.emissive())
                continue;
            const auto& f = mesh.triangles[t];
            Emitter e;
            e.triangle = true;
            e.p0 = Vec3d(mesh.position[f[0]]);
            e.p1 = Vec3d(mesh.position[f[1]]);
            e.p2 = Vec3d(mesh.position[f[2]]);
            const Vec3d c = Cross(e.p1 - e.p0, e.p2 - e.p0);
            e.area = Length(c) / 2;
            e.normal = Normalize(c);
            e.radiance = Vec3d(mat.emission);
            if (e.area > 0)
                emitters.push_back(std::move(e));
        }
        double total = 0;
        for (const Emitter& e : emitters) {
            total += e.area * (e.radiance.x + e.radiance.y + e.radiance.z) * (e.two_sided ? 2 : 1);
            emitter_cdf.push_back(total);
        }
    }

    Vec3d SkyRadiance(const Vec3d& w) const {
        const solve::Sky& sky = scene.sky;
        if (sky.type == solve::Sky::Type::None)
            return {};
        const double c = Dot(Normalize(sky.up), w);
        if (c <= 0)
            return {};
        return sky.type == solve::Sky::Type::Overcast ? sky.radiance * ((1 + 2 * c) / 3) : sky.radiance;
    }

    // Direct light from the emitters at x (one emitter sample): irradiance about n and, if
    // e is not null, vector irradiance. Light below the plane of ng is blocked.
    void Direct(const Vec3d& x, const Vec3d& n, const Vec3d& ng, Rng& rng, Vec3d& irr,
                Vec3d* e) const {
        if (emitters.empty())
            return;
        const double total = emitter_cdf.back();
        const size_t j = std::min(
            size_t(std::upper_bound(emitter_cdf.begin(), emitter_cdf.end(), rng.Uniform() * total) -
                   emitter_cdf.begin()),
            emitters.size() - 1);
        const Emitter& em = emitters[j];
        const double pick = (emitter_cdf[j] - (j ? emitter_cdf[j - 1] : 0)) / total;
        Vec3d y;
        if (!em.Sample(rng, y))
            return;
        const Vec3d o = x + ng * eps;
        const Vec3d d = y - o;
        const double d2 = Dot(d, d);
        if (!(d2 > 0))
            return;
        const Vec3d w = d / std::sqrt(d2);
        if (Dot(w, ng) <= 0)
            return;
        double cos_l = -Dot(w, em.normal);
        if (em.two_sided)
            cos_l = std::abs(cos_l);
        if (cos_l <= 0)
            return;
        solve::Segment s{float(o.x), float(o.y), float(o.z), 0,
                  float(d.x), float(d.y), float(d.z), 1.0f - 1e-4f};
        uint8_t occluded = 0;
        vis.Occluded({&s, 1}, {&occluded, 1});
        rays.fetch_add(1, std::memory_order_relaxed);
        if (occluded)
            return;
        const double g = cos_l / d2 * em.area / pick;
        irr += em.radiance * (g * std::max(0.0, Dot(n, w)));
        if (e)
            for (int c = 0; c < 3; ++c)
                e[c] += w * (em.radiance[c] * g);
    }

    // Radiance arriving at o from direction w, without the emission of sampled emitters
    // (next-event estimation counts it at every vertex instead).
    Vec3d Incoming(Vec3d o, Vec3d w, Rng& rng, const ReferenceOptions& opt) const {
        Vec3d throughput(1, 1, 1), radiance{};
        for (int depth = 0; depth < opt.max_depth; ++depth) {
            solve::Segment s{float(o.x), float(o.y), float(o.z), 0,
                      float(w.x), float(w.y), float(w.z), std::numeric_limits<float>::infinity()};
            solve::Hit h;
            vis.Intersect({&s, 1}, {&h, 1});
            rays.fetch_add(1, std::memory_order_relaxed);
            if (h.prim_id == solve::kNoHit) {
                radiance += Mul(throughput, SkyRadiance(w));
                break;
            }
            const double b[3] = {1.0 - double(h.u) - double(h.v), double(h.u), double(h.v)};
            const Surface sf = SurfaceAt(mesh, scene, h.prim_id, b);
            if (Dot(sf.geometric_normal, w) >= 0)
                break;  // the back of a surface is black
            throughput = Mul(throughput, sf.albedo);
            Vec3d irr{};
            Direct(sf.position, sf.normal, sf.geometric_normal, rng, irr, nullptr);
            radiance += Mul(throughput, irr) * (1 / kPi);
            if (depth + 1 >= opt.roulette_depth) {
                const double q = std::min(0.95, MaxOf(throughput));
                if (!(rng.Uniform() < q))
                    break;
                throughput = throughput / q;
            }
            w = CosineSample(sf.normal, rng.Uniform(), rng.Uniform());
            if (Dot(w, sf.geometric_normal) <= 0)
                break;  // below its own plane: blocked
            o = sf.position + sf.geometric_normal * eps;
        }
        return radiance;
    }

    // One sample of (I, E) at a point: the emitters by next-event estimation, everything
    // else by one direction from the mixture of cosine(n) and uniform(ng hemisphere)
    // densities, so that both the irradiance and the vector estimates have bounded weights.
    void Sample(const ReferencePoint& p, Rng& rng, const ReferenceOptions& opt, Vec3d& irr,
                Vec3d e[3]) const {
        irr = {};
        e[0] = e[1] = e[2] = {};
        Direct(p.position, p.normal, p.geometric_normal, rng, irr, e);
        const Vec3d w = rng.Uniform() < 0.5
                            ? CosineSample(p.normal, rng.Uniform(), rng.Uniform())
                            : UniformHemisphere(p.geometric_normal, rng.Uniform(), rng.Uniform());
        const double cos_n = std::max(0.0, Dot(p.normal, w));
        const double cos_g = Dot(p.geometric_normal, w);
        if (cos_g <= 0)
            return;
        const double pdf = 0.5 * cos_n / kPi + 0.5 / (2 * kPi);
        const Vec3d l = Incoming(p.position + p.geometric_normal * eps, w, rng, opt);
        irr += l * (cos_n / pdf);
        for (int c = 0; c < 3; ++c)
            e[c] += w * (l[c] / pdf);
    }
};

ReferenceTracer::ReferenceTracer(const ReferenceMesh& mesh, const solve::Scene& scene)
    : impl_(std::make_unique<Impl>(mesh, scene)) {}
ReferenceTracer::~ReferenceTracer() = default;

void ReferenceTracer::Intersect(std::span<const solve::Segment> rays,
                                std::span<solve::Hit> hits) const {
    impl_->vis.Intersect(rays, hits);
}

namespace {

// Running sums of one point's samples: B (3) and E (9) values and their squares.
struct Accum {
    double sum[12] = {}, sq[12] = {};
    uint64_t n = 0;
};

}  // namespace

ReferenceStats ReferenceTracer::Estimate(std::vector<ReferencePoint>& points,
                                         const ReferenceOptions& opt,
                                         const std::function<void(int, uint64_t)>& progress) const {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    if (opt.min_samples < 2 || opt.max_samples < opt.min_samples)
        UsageError("reference samples: need 2 <= min_samples <= max_samples");
    impl_->rays = 0;
    std::vector<Accum> acc(points.size());
    std::vector<uint64_t> want(points.size(), opt.min_samples);
    ReferenceStats st;
    double floor = 0;
    double last_round = 0;
    for (int round = 0;; ++round) {
        const auto tr = Clock::now();
        uint64_t paths = 0;
        for (size_t i = 0; i < points.size(); ++i)
            paths += want[i] - acc[i].n;
        ProgressStage stage("reference", paths, "paths");
        stage.SetDetail(fmt::format("round {}", round));
        ParallelFor(0, int64_t(points.size()), [&](int64_t i) {
            ReferencePoint& p = points[size_t(i)];
            Accum& a = acc[size_t(i)];
            const uint64_t paths_here = want[size_t(i)] - a.n;  // for the progress count
            for (uint64_t s = a.n; s < want[size_t(i)]; ++s) {
                Rng rng(opt.seed, p.stream == ReferencePoint::kIndexStream ? uint64_t(i) : p.stream,
                        s);
                Vec3d irr, e[3];
                impl_->Sample(p, rng, opt, irr, e);
                double v[12];
                for (int c = 0; c < 3; ++c) {
                    v[c] = kPi * p.emission[c] + p.albedo[c] * irr[c];
                    for (int k = 0; k < 3; ++k)
                        v[3 + 3 * c + k] = e[c][k];
                }
                for (int k = 0; k < 12; ++k) {
                    a.sum[k] += v[k];
                    a.sq[k] += v[k] * v[k];
                }
            }
            a.n = want[size_t(i)];
            const double n = double(a.n);
            double se[12], mean[12];
            for (int k = 0; k < 12; ++k) {
                mean[k] = a.sum[k] / n;
                const double var = std::max(0.0, a.sq[k] / n - mean[k] * mean[k]) * n / (n - 1);
                se[k] = std::sqrt(var / n);
            }
            for (int c = 0; c < 3; ++c) {
                p.b[c] = mean[c];
                p.b_se[c] = se[c];
                for (int k = 0; k < 3; ++k) {
                    p.e[size_t(c)][k] = mean[3 + 3 * c + k];
                    p.e_se[size_t(c)][k] = se[3 + 3 * c + k];
                }
            }
            p.samples = a.n;
            stage.Add(paths_here);
        });
        stage.Finish();
        ++st.rounds;
        last_round = std::chrono::duration<double>(Clock::now() - tr).count();
        if (round == 0) {
            double s2 = 0;
            for (const auto& p : points)
                s2 += Dot(p.b, p.b);
            floor = opt.floor_fraction * std::sqrt(s2 / double(points.size()));
        }
        uint64_t done = 0, open = 0;
        for (size_t i = 0; i < points.size(); ++i) {
            const ReferencePoint& p = points[i];
            const bool ok =
                Length(p.b_se) <= opt.target_relative_error * std::max(Length(p.b), floor);
            if (ok) {
                ++done;
            } else if (p.samples < opt.max_samples) {
                want[i] = std::min(opt.max_samples, 2 * p.samples);
                ++open;
            }
        }
        st.converged = done;
        if (progress)
            progress(round, done);
        const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
        if (open == 0) {
            st.stop = done == points.size() ? "converged" : "max_samples";
            break;
        }
        // The next round costs about twice the last one: stop if it would not fit.
        if (opt.time_limit > 0 && elapsed + 2 * last_round > opt.time_limit) {
            st.stop = "time_limit";
            break;
        }
    }
    for (const Accum& a : acc)
        st.paths += a.n;
    st.rays = impl_->rays;
    st.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    return st;
}

}  // namespace mebake::reference
