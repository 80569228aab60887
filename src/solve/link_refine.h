// Error-driven stop for the chart-level link refinement: hierarchical radiosity's "BF"
// refinement (Hanrahan et al. 1991; with an error bound per link as in Smits et al. 1994),
// on top of the geometric rule (size / distance <= tau) of Solver::Gatherer::Shoot.
//
// A link (receiver node, emitter region) evaluated where it stands errs by at most the
// irradiance the region can deliver at any point of the node (the link's value and its
// estimate both lie between 0 and that bound), here n . E for the receiver's normals n,
// with the cosines at both ends taken from normal cones of both sides (ConeLinkBound
// below): touching pairs of a gently curved surface get a bound ~ psi^2 instead of the
// half-space's B_max, and pairs facing away get 0 (no link at all). The visibility is not
// known when the link is decided, so its uncertainty is taken as 1.
//
// The link stops when
//
//   bound <= link_tolerance x tolerance x 2^-b x max(E_node, floor x reference)
//
// E_node is the receiver node's own irradiance so far (the mean of its value: direct light
// and the bounces gathered before), so the error allowed is relative to the light already
// at that point, with a floor at a fraction of the scene's brightest direct irradiance
// for points that are nearly black. b is the batch: the errors of coarse links add up over
// the batches (and a coarse near link errs low: point samples of a convex kernel), so the
// allowance halves from batch to batch and their sum stays below twice the first batch's,
// however many batches a bright closed scene needs (without it a furnace at albedo 0.9
// lost 8 %). The unshot radiosity falls faster than that on open scans (about 5x
// per batch on the bunny), so near pairs of dim shooters (late bounces, dark charts) still
// stop at coarse links while bright near pairs keep refining. docs/method.md,
// "Error-driven link refinement".
#pragma once

#include "core/vec.h"

#include <cstddef>
#include <numbers>
#include <vector>

namespace mebake::solve {

class ChartField;

// A bound on the spread of a set of unit normals: every one lies within `angle` (radians)
// of `axis`. angle >= pi/2 says nothing (the normalized mean of such normals need not lie
// in the cone, so the bounds below treat it as any direction).
struct NormalCone {
    Vec3f axis;
    float angle = float(std::numbers::pi);
};
// Cone around `axis` holding every normal of normals[0..count) (zero normals skipped).
NormalCone ConeAround(const Vec3f& axis, const Vec3f* normals, size_t count);
// The smallest cone around `axis` holding both cones.
NormalCone Enclose(const Vec3f& axis, const NormalCone& a, const NormalCone& b);

// One side of a link: a bounding sphere of its points and a cone of their normals.
struct LinkSide {
    Vec3f center;
    float radius = 0;
    NormalCone cone;
};

// A sphere around a few spheres (points: radius 0): centred on their bounding box, often
// much tighter than the geometry pyramid's (centred on the surface point at the texel's
// middle). Get() keeps the fallback sphere when that is not larger.
class SphereBuilder {
public:
    void Add(const Vec3f& c, float r) { parts_.push_back({c, r}); }
    void Get(const Vec3f& fallback_c, float fallback_r, Vec3f* c, float* r) const;

private:
    struct Part {
        Vec3f c;
        float r;
    };
    std::vector<Part> parts_;
};

// Upper bound on n . E, for every normal n of the receiver's cone, that an emitter region
// (largest radiosity db_max, power = integral of its radiosity over its area) gives at any
// receiver point, with the cosines at
// both ends (Sillion's clustering bound with normal cones, plus a bound for touching
// pairs): the kernel only carries light along directions w with w . n_x > 0 (the
// receiver's horizon) and -w . n_y > 0 (the emitter's front side), so
//   - any pair: with both cones widened to a common axis (the bisector of theirs), those
//     directions lie in a band of elevation (-theta_r, theta_e) about the plane normal to
//     it, and n . E <= (db_max / pi) x the integral over the band of the largest n . w
//     <= db_max x min(1, 2 (1 - cos psi)), psi = theta_r + theta_e + the axes' angle:
//     coplanar regions exchange nothing, gently curved neighbours ~ psi^2;
//   - separated spheres (gap d > 0, centres D apart): directions lie within
//     alpha = asin((r_r + r_e) / D) of the centre line u, so
//     n . E <= power / (pi d^2) x max cos at the receiver x max cos at the emitter,
//     zero when either side faces wholly away.
double ConeLinkBound(double db_max, double power, const LinkSide& receiver,
                     const LinkSide& emitter);

// The irradiance scale of a field node's value: the mean over colours of the magnitude of
// its mean E (9 blocks), or the mean B (3 blocks: radiosity, B <= E so it is stricter).
double NodeIrradiance(const ChartField& field, size_t node);

// Per receiver node, the error a link into it may make (0 everywhere when disabled).
class LinkTolerance {
public:
    // Allowed error = scale x max(NodeIrradiance, floor_irradiance); scale <= 0 disables
    // the rule (the purely geometric refinement of before). Solver::LinkToleranceScale()
    // gives link_tolerance x tolerance x 2^-b.
    LinkTolerance(const ChartField& field, double scale, double floor_irradiance);
    bool enabled() const { return !allowed_.empty(); }
    // Whether a link into `node` with irradiance bound `bound` may stop here.
    bool Accepts(size_t node, double bound) const {
        return enabled() && bound <= double(allowed_[node]);
    }
    double allowed(size_t node) const { return allowed_[node]; }

private:
    std::vector<float> allowed_;
};

}  // namespace mebake::solve
