#include "solve/direct.h"

#include "core/check.h"
#include "solve/polygon_light.h"
#include "solve/rays.h"
#include "solve/sky.h"
#include "solve/thread_scratch.h"
#include "solve/visibility.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

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

// What EvaluateLight allocates, kept per thread across calls (it runs per light and node:
// its and AddLights' ~20 vectors' malloc and free were ~2 % of pepper's solve). Every
// vector is assigned or cleared before it is read, so a call computes the same whatever ran
// before it on that thread.
struct LightScratch {
    SegmentBatch batch;
    std::vector<uint8_t> faces, cls, kind, classified, pen_states;
    std::vector<std::pair<size_t, size_t>> asked;
    std::vector<size_t> penumbra;
    std::vector<Vec3d> pen_e, clip_a, clip_b;
};

}  // namespace

std::vector<Vec3d> ClipToHalfSpace(std::span<const Vec3d> poly, const Vec3d& x, const Vec3d& n) {
    std::vector<Vec3d> out(2 * poly.size());
    out.resize(size_t(ClipToHalfSpace(poly.data(), int(poly.size()), x, n, out.data())));
    return out;
}

DirectLight::DirectLight(const Scene& scene, const SolverSettings& settings,
                         const VisibilityScene& vis, float ray_offset, float scene_size,
                         float surface_reach)
    : vis_(vis),
      sky_(scene.sky),
      offset_(ray_offset),
      reach_(surface_reach > 0 ? surface_reach : ray_offset * kOriginReach),
      far_(scene_size * 100),
      outline_face_inside_(settings.outline_face_inside) {
    const int per_tri =
        std::max(2, int(std::ceil(std::sqrt(double(settings.light_samples)) - 1e-9)));
    for (const auto& pl : scene.lights) {
        Light l;
        l.vertices = pl.vertices;
        l.radiance = pl.radiance;
        l.two_sided = pl.two_sided;
        l.normal = PolygonNormal(pl.vertices);
        l.area = PolygonArea(pl.vertices);
        if (l.area <= 0)
            continue;
        Vec3d centre{};
        for (const auto& v : l.vertices)
            centre += v;
        centre = centre / double(l.vertices.size());
        // Classification points: vertices pulled 1% toward the centre, and the centre.
        for (const auto& v : l.vertices)
            l.classify.push_back(Vec3f(v + (centre - v) * 0.01));
        l.classify.push_back(Vec3f(centre));
        // Penumbra grid: per_tri cells per side of each fan triangle, a power of two so
        // that cells halve down to it.
        l.grid = 1;
        while (l.grid < per_tri && l.grid < 64)
            l.grid *= 2;
        const int g1 = l.grid + 1;
        for (size_t t = 0; t + 2 < l.vertices.size(); ++t) {
            for (int b = 0; b < g1; ++b) {
                for (int a = 0; a < g1; ++a) {
                    const Vec3d p =
                        PolygonPoint(l.vertices, t, double(a) / l.grid, double(b) / l.grid);
                    l.grid_pos.push_back(p);
                    l.grid_target.push_back(Vec3f(p + (centre - p) * 0.01));
                    if (l.centre_t < 0 && l.grid_target.back() == l.classify.back())
                        l.centre_t = int(t), l.centre_a = a, l.centre_b = b;
                }
            }
        }
        lights_.push_back(std::move(l));
    }
    if (sky_.type != Sky::Type::None) {
        sky_dirs_ = SkyDirections(settings.sky_directions);
        // The directions turned to the sky's up axis, in float (the rays') and double (the
        // sums'), once for all AddSky calls.
        const Vec3f up(sky_.up);
        Vec3f t, b;
        Frame(up, &t, &b);
        for (const Vec3f& d : sky_dirs_) {
            sky_world_.push_back(t * d.x + b * d.y + up * d.z);
            sky_world_d_.push_back(Vec3d(sky_world_.back()));
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

float DirectLight::SkyDirectionShare() const {
    if (!has_sky() || sky_dirs_.empty())
        return 0;
    const double l = std::max({sky_.radiance.x, sky_.radiance.y, sky_.radiance.z});
    return float(l * 2 * std::numbers::pi / double(sky_dirs_.size()));
}

bool DirectLight::ReachedByALight(const ReceiverPoint& rp) const {
    ReceiverPoint without_face = rp;
    without_face.face = {};
    return std::any_of(lights_.begin(), lights_.end(),
                       [&](const Light& l) { return Faces(l, without_face); });
}

bool DirectLight::Faces(const Light& l, const ReceiverPoint& rp) {
    // E does not involve the receiver's shading normal (that is what keeps it smooth on
    // noisy scans): what lies below the surface is removed by the horizon, the face plane
    // and visibility.
    double side = Dot(Vec3d(rp.position) - l.vertices[0], l.normal);
    bool above = Dot(rp.horizon, rp.horizon) == 0, above_face = Dot(rp.face, rp.face) == 0;
    for (const auto& v : l.vertices) {
        above |= Dot(v - Vec3d(rp.position), Vec3d(rp.horizon)) > 0;
        above_face |= Dot(v - Vec3d(rp.position), Vec3d(rp.face)) > 0;
    }
    return (side > 0 || (l.two_sided && side < 0)) && above && above_face;
}

// One light at the points `which`. prior_cls / prior_grid (may be null): visibility states
// (2 visible, 3 hidden, 0 unknown) of the classification targets / grid vertices taken as
// known for every point, so no ray is spent on them. cls_out / grid_out (may be null)
// receive every point's states, for use as a prior elsewhere: a fully lit point counts as
// seeing every vertex, an umbra point none, a point the light cannot reach is unknown.
void DirectLight::EvaluateLight(const Light& l, std::span<const ReceiverPoint> points,
                                std::span<const size_t> which, const uint8_t* prior_cls,
                                const uint8_t* prior_grid, std::span<float> out,
                                std::vector<uint8_t>* cls_out,
                                std::vector<uint8_t>* grid_out) const {
    const size_t nk = l.classify.size();
    const size_t nv = (l.vertices.size() - 2) * size_t(l.grid + 1) * size_t(l.grid + 1);
    ThreadScratch<LightScratch> kept;
    LightScratch& scratch = *kept;
    // 1. Classify each point with a few rays (skip points the light cannot reach).
    SegmentBatch& batch = scratch.batch;
    batch.Clear();
    std::vector<uint8_t>& faces = scratch.faces;
    std::vector<uint8_t>& cls = scratch.cls;
    faces.assign(which.size(), 0);
    cls.assign(which.size() * nk, 0);
    std::vector<std::pair<size_t, size_t>>& asked = scratch.asked;
    asked.clear();
    for (size_t q = 0; q < which.size(); ++q) {
        const auto& rp = points[which[q]];
        faces[q] = Faces(l, rp);
        if (!faces[q])
            continue;
        const Vec3f o = rp.vis_point + rp.normal * offset_;
        for (size_t k = 0; k < nk; ++k) {
            if (prior_cls && prior_cls[k] != 0) {
                cls[q * nk + k] = prior_cls[k];
                continue;
            }
            asked.push_back({q, k});
            batch.AddSegment(o, l.classify[k]);
        }
    }
    batch.Trace(vis_, RayKind::kClassify);
    for (size_t r = 0; r < asked.size(); ++r)
        cls[asked[r].first * nk + asked[r].second] = batch.occluded[r] ? 3 : 2;
    enum : uint8_t { kAway, kLit, kUmbra, kPenumbra };
    std::vector<uint8_t>& kind = scratch.kind;
    kind.assign(which.size(), kAway);
    std::vector<size_t>& penumbra = scratch.penumbra;
    penumbra.clear();
    // Per penumbra point: occluded[] of its classify rays.
    std::vector<uint8_t>& classified = scratch.classified;
    classified.clear();
    for (size_t q = 0; q < which.size(); ++q) {
        if (!faces[q])
            continue;
        size_t vis = 0;
        for (size_t k = 0; k < nk; ++k)
            vis += cls[q * nk + k] == 2 ? 1 : 0;
        kind[q] = vis == nk ? kLit : vis == 0 ? kUmbra : kPenumbra;
        if (kind[q] != kPenumbra)
            continue;
        penumbra.push_back(which[q]);
        for (size_t k = 0; k < nk; ++k)
            classified.push_back(cls[q * nk + k] == 3 ? 1 : 0);
    }
    // 2. Penumbra points: adaptive cells of the light (see Penumbra()).
    std::vector<Vec3d>& pen_e = scratch.pen_e;  // assigned by Penumbra
    std::vector<uint8_t>& pen_states = scratch.pen_states;
    const bool centre_traced = !prior_cls || prior_cls[nk - 1] == 0;
    Penumbra(l, points, penumbra, classified, centre_traced, prior_grid, &pen_e,
             grid_out ? &pen_states : nullptr);
    auto add = [&](size_t p, const Vec3d& e) {
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k)
                out[p * 9 + size_t(3 * c + k)] += float(l.radiance[c] * e[k]);
    };
    for (size_t q = 0; q < penumbra.size(); ++q)
        add(penumbra[q], pen_e[q]);
    // 3. Fully lit points: the closed form above the point's horizon.
    const Emission emission = l.two_sided ? Emission::kBoth : Emission::kFront;
    std::vector<Vec3d>& clip_a = scratch.clip_a;
    std::vector<Vec3d>& clip_b = scratch.clip_b;
    clip_a.resize(std::max(clip_a.size(), 2 * l.vertices.size()));
    clip_b.resize(std::max(clip_b.size(), 4 * l.vertices.size()));
    for (size_t q = 0; q < which.size(); ++q) {
        if (kind[q] != kLit)
            continue;
        const size_t p = which[q];
        const Vec3d x(points[p].position), h(points[p].horizon), f(points[p].face);
        // Clipped in place of two buffers (no allocation per point): each clip at most
        // doubles the vertex count.
        const Vec3d* poly = l.vertices.data();
        int n = int(l.vertices.size());
        for (const Vec3d& plane : {h, f}) {
            if (Dot(plane, plane) > 0 && n >= 3) {
                Vec3d* dst = poly == clip_a.data() ? clip_b.data() : clip_a.data();
                n = ClipToHalfSpace(poly, n, x, plane, dst);
                poly = dst;
            }
        }
        if (n >= 3)
            add(p, VectorIrradiance({poly, size_t(n)}, 1.0, x, emission));
    }
    if (cls_out) {
        cls_out->assign(which.size() * nk, 0);
        for (size_t q = 0; q < which.size(); ++q)
            if (faces[q])
                std::copy(&cls[q * nk], &cls[q * nk] + nk, &(*cls_out)[q * nk]);
    }
    if (grid_out) {
        grid_out->assign(which.size() * nv, 0);
        size_t at = 0;
        for (size_t q = 0; q < which.size(); ++q) {
            uint8_t* g = &(*grid_out)[q * nv];
            if (kind[q] == kLit || kind[q] == kUmbra)
                std::fill(g, g + nv, kind[q] == kLit ? 2 : 3);
            if (kind[q] == kPenumbra)
                std::copy(&pen_states[at * nv], &pen_states[(at + 1) * nv], g), ++at;
        }
    }
}

void DirectLight::Evaluate(std::span<const ReceiverPoint> points, std::span<float> out, int parts,
                           size_t probes, ProbeCache* cache, std::span<const ProbeKey> keys,
                           std::span<const uint8_t> known,
                           std::span<const uint8_t> inherited) const {
    CHECK_EQ(out.size(), points.size() * 9);
    if (!known.empty())
        CHECK_EQ(known.size(), lights_.size());
    std::fill(out.begin(), out.end(), 0.f);
    if (cache)
        CHECK_EQ(keys.size(), probes);
    const bool with_sky = sky_.type != Sky::Type::None && (parts & kSky);
    // Probes found in the cache take their E and states from it (AddLights) and their
    // visibility points are never read: they are not moved (no origin rays). Unless a light
    // is known: it is evaluated at every point, found probes too.
    // Each probe is looked up once, here; AddLights takes the records found (one per probe
    // when probes are used, null where not found or without a cache).
    const bool coherent = probes > 0 && probes < points.size();
    std::vector<const ProbeCache::Record*> records(coherent ? probes : 0, nullptr);
    if (cache && coherent) {
        for (size_t q = 0; q < probes; ++q) {
            auto it = cache->map_.find(keys[q]);
            if (it != cache->map_.end())
                records[q] = &it->second;
        }
    }
    std::vector<uint8_t> found;
    const bool none_known =
        std::all_of(known.begin(), known.end(), [](uint8_t k) { return k == 0; });
    if (cache && coherent && !with_sky && none_known) {
        found.assign(points.size(), 0);
        for (size_t q = 0; q < probes; ++q)
            found[q] = records[q] ? 1 : 0;
    }
    const std::vector<ReceiverPoint> on_surface = OnSurface(points, !with_sky, found);
    if (parts & kLights)
        AddLights(on_surface, out, probes, cache, keys, known, inherited, records);
    if (with_sky)
        AddSky(on_surface, out);
}

void DirectLight::EvaluateSky(std::span<const ReceiverPoint> points, std::span<float> out,
                              std::span<const uint8_t> prior, std::vector<uint8_t>* states) const {
    CHECK_EQ(out.size(), points.size() * 9);
    std::fill(out.begin(), out.end(), 0.f);
    if (has_sky())
        AddSky(OnSurface(points), out, prior, states);
}

bool DirectLight::ShadowEdgeAmong(std::span<const ReceiverPoint> points) const {
    const std::vector<ReceiverPoint> on_surface = OnSurface(points, true);
    for (const auto& l : lights_) {
        // A point whose own face turns from the light's centre counts as hidden: the
        // surface shades itself there (a fold turning away), an edge to refine as well.
        SegmentBatch batch;
        size_t below = 0;
        for (const auto& rp : on_surface) {
            ReceiverPoint without_face = rp;
            without_face.face = {};
            if (!Faces(l, without_face))
                continue;
            if (Dot(l.classify.back() - rp.position, rp.face) < 0)
                ++below;
            else
                batch.AddSegment(rp.vis_point + rp.normal * offset_, l.classify.back());
        }
        batch.Trace(vis_, RayKind::kClassify);
        const size_t hidden =
            below + size_t(std::count(batch.occluded.begin(), batch.occluded.end(), 1));
        if (hidden > 0 && hidden < below + batch.size())
            return true;
    }
    return false;
}

// A receiver's visibility point is interpolated between geometry-image texel centres, and
// that chord leaves the real surface where it turns within a texel: on a convex bend it
// runs under it (a rim, a fold of drapery), and rays from there hit the surface they leave
// (nefertiti under the sky alone: whole nodes at 7 % of their sky, bench/RESULTS.md, "Issue
// 14 (session 7)"); in a concave one it floats above it (the crevices of nefertiti's crown),
// and rays from there pass over the rim that shades the real point ("Issue 14 (session
// 8)"). Rays along the normal find out. Leaving through the back of a triangle within
// `reach_` means the point is under the surface: it moves up to where the ray left. Else a
// ray the other way meeting the front of a triangle within `reach_` means it is above: it
// moves down onto it.
std::vector<ReceiverPoint> DirectLight::OnSurface(std::span<const ReceiverPoint> points,
                                                   bool lights_only,
                                                   std::span<const uint8_t> skip) const {
    std::vector<ReceiverPoint> out(points.begin(), points.end());
    // The buffers per thread (OnSurface runs per node and pass); each is assigned or cleared
    // before it is read.
    struct Scratch {
        std::vector<size_t> which, moved, still, traced;
        std::vector<Hit> onto, hits;
        std::vector<Segment> segs;
    };
    ThreadScratch<Scratch> kept;
    Scratch& scratch = *kept;
    std::vector<size_t>& which = scratch.which;
    which.clear();
    for (size_t p = 0; p < points.size(); ++p)
        if ((skip.empty() || !skip[p]) && (!lights_only || ReachedByALight(points[p])))
            which.push_back(p);
    std::vector<size_t>& moved = scratch.moved;
    moved.assign(which.begin(), which.end());
    // The triangle each point moved onto (its ray's hit; geom_id kNoHit: not moved).
    std::vector<Hit>& onto = scratch.onto;
    onto.assign(points.size(), Hit{});
    std::vector<Segment>& segs = scratch.segs;
    std::vector<Hit>& hits = scratch.hits;
    for (float dir : {1.f, -1.f}) {
        segs.resize(which.size());
        for (size_t k = 0; k < which.size(); ++k) {
            const Vec3f& o = points[which[k]].vis_point;
            const Vec3f n = points[which[k]].normal * dir;
            segs[k] = Segment{o.x, o.y, o.z, 0.f, n.x, n.y, n.z, reach_};
        }
        hits.assign(which.size(), Hit{});
        TraceHits(vis_, segs, hits, RayKind::kOrigin);
        std::vector<size_t>& still = scratch.still;  // not moved: looked at the other way
        still.clear();
        for (size_t k = 0; k < which.size(); ++k) {
            const ReceiverPoint& rp = points[which[k]];
            const Hit& h = hits[k];
            // The back of a triangle going up, its front going down: ng along the normal.
            if (h.geom_id != kNoHit && Dot(Vec3f(h.ng_x, h.ng_y, h.ng_z), rp.normal) > 0) {
                out[which[k]].vis_point = rp.vis_point + rp.normal * (dir * h.t);
                onto[which[k]] = h;
            } else {
                still.push_back(which[k]);
            }
        }
        which.swap(still);
    }
    // The face under each shadow-ray origin: light below its plane is blocked by the
    // surface itself (the path tracer's rule, reference.cpp). The horizon's continuous
    // normal field turns between vertex normals, and across a fold of large triangles a
    // face can tilt from it by 15 degrees or more: grazing key light the face cannot see
    // counted in full there (lucy's worst point, bench/RESULTS.md "Issue 14 (session 9)").
    // An outline point's visibility point lies on the edge its chart shares with the
    // neighbour, and the ray from there may meet either side: across a bend the
    // neighbour's plane cut light the chart's own border points see (lucy, bench/
    // RESULTS.md "Issue 14 (session 15)"). With outline_face_inside the ray starts half a
    // light-map texel inside the chart (toward the visibility point from the virtual
    // position), so the face is the chart's own real edge, whose cut its real points have
    // too (a key grazing that edge stays cut: turbineblade, session 16).
    // A point that moved onto a triangle along its normal sits on it, and the face ray
    // (the same line, from just above) meets that triangle first at 99.6 % of them (pepper):
    // its plane is taken without the ray. The others (not moved, or outline points whose
    // ray starts inside the chart) trace it.
    std::vector<size_t>& traced = scratch.traced;
    traced.clear();
    segs.clear();
    for (size_t p : moved) {
        const ReceiverPoint& rp = out[p];
        if (onto[p].geom_id != kNoHit && !(outline_face_inside_ && rp.outline))
            continue;
        Vec3f o = rp.vis_point + rp.normal * offset_;
        if (outline_face_inside_ && rp.outline)
            o = o + Inward(rp) * offset_;
        const Vec3f n = rp.normal * -1.f;
        segs.push_back(Segment{o.x, o.y, o.z, 0.f, n.x, n.y, n.z, 2 * offset_});
        traced.push_back(p);
    }
    hits.assign(traced.size(), Hit{});
    TraceHits(vis_, segs, hits, RayKind::kOrigin);
    for (size_t k = 0; k < traced.size(); ++k)
        onto[traced[k]] = hits[k];
    for (size_t p : moved) {
        ReceiverPoint& rp = out[p];
        const Hit& h = onto[p];
        const Vec3f ng(h.ng_x, h.ng_y, h.ng_z);
        // Visibility-only points (no horizon) stay as they are.
        if (h.geom_id != kNoHit && Dot(ng, rp.normal) > 0 && Dot(rp.horizon, rp.horizon) > 0)
            rp.face = Normalize(ng);
    }
    return out;
}

std::vector<uint8_t> DirectLight::ProbeAgreement(const ProbeCache& cache,
                                                 std::span<const ProbeKey> keys) const {
    std::vector<uint8_t> agree;
    for (const ProbeKey& key : keys) {
        auto it = cache.map_.find(key);
        if (it == cache.map_.end())
            return {};
        const std::vector<uint8_t>& st = it->second.states;
        if (agree.empty())
            agree = st;
        for (size_t k = 0; k < agree.size(); ++k)
            if (st[k] != agree[k])
                agree[k] = 0;
    }
    return agree;
}

// Every light at the points. With probes (the first `probes` points surround one small
// patch), the probes are evaluated first, or found in the cache; where all of them agree
// on a light vertex's visibility, the other points take it without a ray.
void DirectLight::AddLights(std::span<const ReceiverPoint> points, std::span<float> out,
                            size_t probes, ProbeCache* cache, std::span<const ProbeKey> keys,
                            std::span<const uint8_t> known,
                            std::span<const uint8_t> inherited,
                            std::span<const ProbeCache::Record* const> found) const {
    const bool coherent = probes > 0 && probes < points.size();
    // AddLights' own buffers, per thread as EvaluateLight's (LightScratch): alive across
    // its EvaluateLight calls.
    struct Scratch {
        std::vector<float> probe_e;
        std::vector<size_t> others, all, uncached;
        std::vector<uint8_t> prior, cls, grid, st;
    };
    ThreadScratch<Scratch> kept;
    Scratch& scratch = *kept;
    // Probes found in the cache (`found`, from Evaluate), and records for the others
    // (filled light by light).
    if (coherent)
        CHECK_EQ(found.size(), probes);
    std::vector<ProbeCache::Record> fresh(coherent ? probes : 0);
    size_t state_at = 0;  // this light's offset in a record's states
    std::vector<float>& probe_e = scratch.probe_e;
    // Without probes every point is evaluated on its own; with them, the points after the
    // probes take the probes' agreement as a prior.
    std::vector<size_t>& others = scratch.others;
    others.resize(points.size() - (coherent ? probes : 0));
    std::iota(others.begin(), others.end(), coherent ? probes : 0);
    for (const auto& l : lights_) {
        const size_t li = size_t(&l - lights_.data());
        if (!known.empty() && known[li] != 0) {
            // Known visible or hidden: every point (probes too) without a ray; fresh probe
            // records get this light's E and uniform states so the record layout holds.
            const size_t nk = l.classify.size();
            const size_t nv = (l.vertices.size() - 2) * size_t(l.grid + 1) * size_t(l.grid + 1);
            std::vector<uint8_t>& prior = scratch.prior;
            prior.assign(nk + nv, known[li]);
            std::vector<size_t>& all = scratch.all;
            all.resize(points.size());
            std::iota(all.begin(), all.end(), size_t(0));
            probe_e.assign(out.size(), 0.f);
            EvaluateLight(l, points, all, prior.data(), prior.data() + nk, probe_e, nullptr,
                          nullptr);
            for (size_t k = 0; k < out.size(); ++k)
                out[k] += probe_e[k];
            if (coherent) {
                for (size_t q = 0; q < probes; ++q) {
                    if (found[q])
                        continue;
                    fresh[q].e.insert(fresh[q].e.end(), &probe_e[q * 9], &probe_e[q * 9] + 9);
                    fresh[q].states.insert(fresh[q].states.end(), prior.begin(), prior.end());
                }
                state_at += nk + nv;
            }
            continue;
        }
        if (!coherent) {
            EvaluateLight(l, points, others, nullptr, nullptr, out, nullptr, nullptr);
            continue;
        }
        // Points of one small patch: the probes are evaluated first; where all of them agree
        // on a light vertex's visibility, the other points take it without a ray.
        const size_t nk = l.classify.size();
        const size_t nv = (l.vertices.size() - 2) * size_t(l.grid + 1) * size_t(l.grid + 1);
        std::vector<size_t>& uncached = scratch.uncached;  // probes not in the cache: traced
        uncached.clear();
        for (size_t q = 0; q < probes; ++q)
            if (!found[q])
                uncached.push_back(q);
        std::vector<uint8_t>& cls = scratch.cls;  // assigned by EvaluateLight
        std::vector<uint8_t>& grid = scratch.grid;
        probe_e.assign(out.size(), 0.f);
        const uint8_t* inh = inherited.empty() ? nullptr : &inherited[state_at];
        EvaluateLight(l, points, uncached, inh, inh ? inh + nk : nullptr, probe_e, &cls, &grid);
        // Every probe's states (nk then nv), cached or new; E added to out.
        std::vector<uint8_t>& st = scratch.st;  // every slot written below
        st.resize(probes * (nk + nv));
        for (size_t q = 0, t = 0; q < probes; ++q) {
            uint8_t* dst = &st[q * (nk + nv)];
            const float* e;
            if (found[q]) {
                std::copy(&found[q]->states[state_at], &found[q]->states[state_at + nk + nv], dst);
                e = &found[q]->e[9 * size_t(&l - lights_.data())];
            } else {
                std::copy(&cls[t * nk], &cls[(t + 1) * nk], dst);
                std::copy(&grid[t * nv], &grid[(t + 1) * nv], dst + nk);
                e = &probe_e[q * 9];
                fresh[q].e.insert(fresh[q].e.end(), e, e + 9);
                fresh[q].states.insert(fresh[q].states.end(), dst, dst + nk + nv);
                ++t;
            }
            for (int k = 0; k < 9; ++k)
                out[q * 9 + size_t(k)] += e[k];
        }
        std::vector<uint8_t>& prior = scratch.prior;
        prior.assign(st.begin(), st.begin() + std::ptrdiff_t(nk + nv));
        for (size_t q = 1; q < probes; ++q)
            for (size_t k = 0; k < nk + nv; ++k)
                if (st[q * (nk + nv) + k] != prior[k])
                    prior[k] = 0;
        EvaluateLight(l, points, others, prior.data(), prior.data() + nk, out, nullptr, nullptr);
        state_at += nk + nv;
    }
    if (coherent && cache) {
        for (size_t q = 0; q < probes; ++q)
            if (!found[q])
                cache->map_.emplace(keys[q], std::move(fresh[q]));
    }
}

// The sky at the points: one ray per fixed direction (sky.h), turned to the sky's up axis,
// so E changes with position only where visibility does. The sky's uniform part is a control
// variate: its integral over the directions above the point's planes (the sky's horizon, the
// point's horizon and face) is taken in closed form and only the directions found occluded
// there are subtracted, so a point that sees its whole sky is exact and its E turns smoothly
// with its planes instead of in steps as they pass the fixed directions (docs/method.md,
// "The sky").
void DirectLight::AddSky(std::span<const ReceiverPoint> points, std::span<float> out,
                         std::span<const uint8_t> prior, std::vector<uint8_t>* states) const {
    if (!prior.empty())
        CHECK_EQ(prior.size(), sky_dirs_.size());
    // The batch and the states per thread (AddSky runs per node: no malloc per call).
    struct Scratch {
        SegmentBatch batch;
        std::vector<uint8_t> state;
    };
    ThreadScratch<Scratch> kept;
    SegmentBatch& batch = kept->batch;
    std::vector<uint8_t>& state = kept->state;
    batch.Clear();
    const Vec3f up(sky_.up);
    const std::vector<Vec3f>& dirs = sky_world_;
    // Per point and direction: seen, occluded, below its planes (no ray), or traced.
    constexpr uint8_t kTraced = 3;
    state.resize(points.size() * dirs.size());  // every entry written below
    for (size_t p = 0; p < points.size(); ++p) {
        const ReceiverPoint& rp = points[p];
        const Vec3f o = rp.vis_point + rp.normal * offset_;
        for (size_t k = 0; k < dirs.size(); ++k) {
            uint8_t& s = state[p * dirs.size() + k];
            if (!AboveSurface(rp, dirs[k])) {
                s = kSkyBelow;
            } else if (!prior.empty() && prior[k] <= 1) {
                s = prior[k];
            } else {
                s = kTraced;
                batch.Add(o, dirs[k], far_);
            }
        }
    }
    batch.Trace(vis_, RayKind::kSky);
    for (size_t i = 0, r = 0; i < state.size(); ++i)
        if (state[i] == kTraced)
            state[i] = batch.occluded[r++] ? 1 : 0;
    if (states)
        states->assign(state.begin(), state.end());
    // Estimator of E = integral of L(w) V w dw with the uniform pdf 1 / (2 pi):
    // sum L w 2 pi / N; the uniform part a: a (closed form above the planes - sum of the
    // occluded directions above them), the overcast's (2/3) Lz cos part by the sum.
    const double scale = 2 * std::numbers::pi / double(sky_dirs_.size());
    const bool overcast = sky_.type == Sky::Type::Overcast;
    const Vec3d uniform = sky_.radiance * (overcast ? 1.0 / 3.0 : 1.0);
    // Per direction, once for all points: the overcast's factor per colour (the same
    // products as per point, so the same bits).
    const std::vector<Vec3d>& wd = sky_world_d_;
    std::vector<Vec3d> cos_part(overcast ? dirs.size() : 0);
    for (size_t k = 0; k < cos_part.size(); ++k)
        for (int c = 0; c < 3; ++c)
            cos_part[k][c] = sky_.radiance[c] * (2.0 / 3.0) * double(sky_dirs_[k].z) * scale;
    for (size_t p = 0; p < points.size(); ++p) {
        const ReceiverPoint& rp = points[p];
        const std::array<Vec3d, 3> planes = {Vec3d(up), Vec3d(rp.horizon), Vec3d(rp.face)};
        Vec3d e[3] = {};  // per colour: the overcast's cos part
        Vec3d occluded{};  // sum of occluded directions above the planes
        const uint8_t* st = &state[p * dirs.size()];
        for (size_t k = 0; k < dirs.size(); ++k) {
            const uint8_t s = st[k];
            if (s == kSkyBelow)
                continue;  // outside the closed form's region
            const Vec3d& w = wd[k];
            if (s == 1) {
                occluded += w;
                continue;
            }
            if (overcast)
                for (int c = 0; c < 3; ++c)
                    e[c] += w * cos_part[k][c];
        }
        const Vec3d open = HalfSpacesVector(planes) - occluded * scale;
        for (int c = 0; c < 3; ++c) {
            const Vec3d ec = e[c] + open * uniform[c];
            for (int k = 0; k < 3; ++k)
                out[p * 9 + size_t(3 * c + k)] += float(ec[k]);
        }
    }
}

}  // namespace mebake::solve
