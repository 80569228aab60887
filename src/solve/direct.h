// Direct light at receiver points: polygonal area lights by Lambert's closed form
// with visibility classified per point (lit, umbra or penumbra, in the spirit of seed
// 002's extremal-boundary pass: a few rays decide, many rays only in penumbra), and the
// sky by uniform directions stratified in height and azimuth (the bent normal times the unoccluded
// fraction, in effect).
#pragma once

#include "core/vec.h"
#include "solve/scene.h"

#include <array>
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

namespace mebake::solve {

class VisibilityScene;

struct ReceiverPoint {
    Vec3f position;   // where the field is evaluated
    Vec3f normal;     // surface normal there (offsets shadow rays)
    Vec3f vis_point;  // where visibility is evaluated (nearest real point)
    // The horizon: light below the plane through the point with this normal is cut off
    // in closed form. Callers pass a smooth normal (the quadtree node's), not the scan's
    // noisy per-point one, so E stays smooth; zero means no horizon (visibility only).
    Vec3f horizon{};
    // The plane of the real surface at the visibility point (the face there; set by
    // DirectLight itself): light below it is blocked by the surface, as in the path
    // tracer. Zero: not known (no cut).
    Vec3f face{};
    // A virtual point (the seed's x' rule): its position is extrapolated past the chart's
    // real part and its visibility point lies on the chart's outline (Solver::PointAt).
    bool outline = false;
};

// The direction into a virtual point's chart at its visibility point: from the
// extrapolated position toward it, in the plane across the normal (zero where they
// coincide).
inline Vec3f Inward(const ReceiverPoint& rp) {
    Vec3f d = rp.vis_point - rp.position;
    d = d - rp.normal * Dot(d, rp.normal);
    const float len = Length(d);
    return len > 0 ? d * (1.f / len) : Vec3f{};
}

// Whether direction w (from the point) lies above its horizon and its face plane.
inline bool AboveSurface(const ReceiverPoint& rp, const Vec3f& w) {
    return Dot(w, rp.horizon) >= 0 && Dot(w, rp.face) >= 0;
}

// Where a probe point sits, to find it again: the chart's geometry level it was sampled at
// and its chart coordinates (exact float bits; node corners shared by neighbours, parents
// and children compute the same values).
struct ProbeKey {
    uint32_t u = 0, v = 0, level = 0;
    uint32_t known = 0;  // the lights taken as known (Evaluate's `known`), as a code
    bool operator==(const ProbeKey&) const = default;
};
struct ProbeKeyHash {
    size_t operator()(const ProbeKey& k) const {
        return size_t((uint64_t(k.u) * 0x9E3779B97F4A7C15ull) ^
                      (uint64_t(k.v) * 0xC2B2AE3D27D4EB4Full) ^ k.level ^ (size_t(k.known) << 8));
    }
};

// Results of probes kept across Evaluate calls on one chart: a node's corner probes are
// its neighbours', its parent's and its children's too. Per light: E and visibility states.
class ProbeCache {
public:
    void Clear() { map_.clear(); }
    size_t size() const { return map_.size(); }

private:
    friend class DirectLight;
    struct Record {
        std::vector<float> e;         // 9 per light
        std::vector<uint8_t> states;  // per light: classification then grid vertex states
    };
    std::unordered_map<ProbeKey, Record, ProbeKeyHash> map_;
};

class DirectLight {
public:
    // How far under the surface a visibility point is looked for, in half light-map texels
    // (Solver::RayOffset): four texels, one to four geometry-image texels.
    static constexpr float kOriginReach = 8;
    // Sampling counts come from `settings` (light_samples, sky_directions). Rays start
    // ray_offset off the surface; a visibility point up to surface_reach under it moves up
    // onto it first (OnSurface; 0: kOriginReach x ray_offset).
    DirectLight(const Scene& scene, const SolverSettings& settings, const VisibilityScene& vis,
                float ray_offset, float scene_size, float surface_reach = 0);

    enum Parts { kLights = 1, kSky = 2, kAll = 3 };
    // E (3 colours x 3 components, out[9*p + 3*c + k]) at each point, from the parts asked.
    // probes > 0: the points lie on one small patch and the first `probes` of them surround
    // it; where all probes agree on the visibility of a light's vertex (or sub-cell corner),
    // the other points take it without tracing (reuse of visibility across a patch).
    // With a cache and one key per probe, probes found there cost no ray (same result).
    // known (empty, or one state per light): 2 = the light is taken as fully visible at
    // every point (closed form, no ray), 3 = as hidden (no contribution, no ray), 0 = traced
    // as usual. The multi-emitter pass (extremal_boundary.h) supplies it.
    // inherited (empty, or every light's classification then grid vertex states, as
    // ProbeAgreement returns): states taken as known at the probes not found in the cache.
    void Evaluate(std::span<const ReceiverPoint> points, std::span<float> out, int parts = kAll,
                  size_t probes = 0, ProbeCache* cache = nullptr,
                  std::span<const ProbeKey> keys = {}, std::span<const uint8_t> known = {},
                  std::span<const uint8_t> inherited = {}) const;
    // Where the cached probes `keys` agree: per light, its classification targets' then its
    // grid vertices' states where every probe has the same one, 0 elsewhere (Evaluate's
    // `inherited`). Empty if one of them is not in the cache.
    std::vector<uint8_t> ProbeAgreement(const ProbeCache& cache,
                                        std::span<const ProbeKey> keys) const;
    bool has_lights() const { return !lights_.empty(); }
    size_t light_count() const { return lights_.size(); }
    // Per point, light `light` as seen with its classification rays only (no penumbra
    // rays): kPointAway (the light cannot reach it), kPointLit, kPointUmbra, kPointPenumbra.
    // extremal_boundary.cpp.
    enum PointClass : uint8_t { kPointAway, kPointLit, kPointUmbra, kPointPenumbra };
    void ClassifyPoints(size_t light, std::span<const ReceiverPoint> points,
                        std::vector<uint8_t>* kind) const;
    // Whether some light is seen from some of the points and hidden from others that it
    // faces (one ray per point to the light's centre): a shadow edge among them.
    bool ShadowEdgeAmong(std::span<const ReceiverPoint> points) const;
    bool has_sky() const { return sky_.type != Sky::Type::None; }
    // The sky alone at the points, as Evaluate(points, out, kSky) but for two things. prior
    // (empty, or one per sky direction): 0 or 1 is taken as that direction's visibility
    // (seen, occluded) wherever it is above a point's planes, without a ray; anything else is
    // traced. states (may be null): per point and direction, 0 seen, 1 occluded, 2 below the
    // point's planes (kSkyBelow).
    static constexpr uint8_t kSkyBelow = 2;
    void EvaluateSky(std::span<const ReceiverPoint> points, std::span<float> out,
                     std::span<const uint8_t> prior, std::vector<uint8_t>* states) const;
    size_t sky_direction_count() const { return sky_dirs_.size(); }
    // The most one sky direction adds to a component of E: the sky's largest radiance times
    // the solid angle a direction stands for (2 pi / N).
    float SkyDirectionShare() const;
    bool empty() const { return !has_lights() && !has_sky(); }
    // Power leaving the emitters (W), for the stopping rule and energy checks.
    double EmittedPower() const;

private:
    struct Light {
        std::vector<Vec3d> vertices;
        Vec3d radiance;
        bool two_sided;
        Vec3d normal;
        double area;
        std::vector<Vec3f> classify;  // few sample points: corners pulled in, centre
        // Penumbrae: each fan triangle (v0, v[t+1], v[t+2]) carries a barycentric grid of
        // `grid` cells per side. Cells are refined from a coarse level only where the
        // visibility of their corners disagrees (a shadow edge crosses them); a finest cell
        // with mixed corners counts as 1/4 or 3/4 visible (one or two corners visible), or,
        // where the edge runs along a row of cells, as one fixed low-discrepancy point in it is.
        int grid = 8;
        std::vector<Vec3d> grid_pos;     // [t][b][a] exact grid vertices, (grid+1)^2 per t
        std::vector<Vec3f> grid_target;  // the same pulled 1% toward the centre (ray ends)
        // The grid vertex (fan triangle, a, b) whose ray end is the classification's centre
        // to the bit (a parallelogram's centre, on the diagonal), or t < 0: its penumbra ray
        // would be the centre's classification ray again (Penumbra reuses that answer).
        int centre_t = -1, centre_a = 0, centre_b = 0;
    };
    void EvaluateLight(const Light& l, std::span<const ReceiverPoint> points,
                       std::span<const size_t> which, const uint8_t* prior_cls,
                       const uint8_t* prior_grid, std::span<float> out,
                       std::vector<uint8_t>* cls_out, std::vector<uint8_t>* grid_out) const;
    // found (one per probe when 0 < probes < points): the probes' cache records, null where
    // not found or without a cache (Evaluate looks them up).
    void AddLights(std::span<const ReceiverPoint> points, std::span<float> out, size_t probes,
                   ProbeCache* cache, std::span<const ProbeKey> keys,
                   std::span<const uint8_t> known, std::span<const uint8_t> inherited,
                   std::span<const ProbeCache::Record* const> found) const;
    // Whether light l can reach the point at all (its side, above the point's horizon).
    static bool Faces(const Light& l, const ReceiverPoint& rp);
    void AddSky(std::span<const ReceiverPoint> points, std::span<float> out,
                std::span<const uint8_t> prior = {}, std::vector<uint8_t>* states = nullptr) const;
    // Whether some light reaches the point by its side and horizon (Faces without its face
    // plane): where none does, no light's result depends on where its visibility point is.
    bool ReachedByALight(const ReceiverPoint& rp) const;
    // The points with their visibility points moved onto the real surface where they lie
    // under or above it (one ray each along the normal, at most reach_ long), and, for
    // points with a horizon, the plane of the face under their shadow-ray origin (`face`).
    // lights_only: only the points some light reaches (the others as they are; no ray).
    // With outline_face_inside, an outline point's face is looked for just inside its chart.
    // skip (empty, or one per point): points left as they are (no ray).
    std::vector<ReceiverPoint> OnSurface(std::span<const ReceiverPoint> points,
                                         bool lights_only = false,
                                         std::span<const uint8_t> skip = {}) const;
    class PenumbraPass;  // penumbra.cpp
    // centre_traced: every point's centre state in `classified` is its own ray's answer
    // (not taken from a prior).
    void Penumbra(const Light& l, std::span<const ReceiverPoint> points,
                  std::span<const size_t> penumbra, std::span<const uint8_t> classified,
                  bool centre_traced, const uint8_t* prior, std::vector<Vec3d>* e,
                  std::vector<uint8_t>* states) const;
    const VisibilityScene& vis_;
    std::vector<Light> lights_;
    Sky sky_;
    std::vector<Vec3f> sky_dirs_;     // uniform directions about +z, stratified in z and azimuth
    std::vector<Vec3f> sky_world_;    // sky_dirs_ turned to the sky's up axis
    std::vector<Vec3d> sky_world_d_;  // the same in double
    float offset_, reach_, far_;
    bool outline_face_inside_;  // SolverSettings::outline_face_inside
};

// ClipToHalfSpace of polygon_light.h, returning the clipped polygon.
std::vector<Vec3d> ClipToHalfSpace(std::span<const Vec3d> poly, const Vec3d& x, const Vec3d& n);

}  // namespace mebake::solve
