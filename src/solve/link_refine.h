// Error-driven stop for the chart-level link refinement: hierarchical radiosity's "BF"
// refinement (Hanrahan et al. 1991; with an error bound per link as in Smits et al. 1994),
// on top of the geometric rule (size / distance <= tau) of Solver::Gatherer::Shoot.
//
// A link (receiver node, emitter region) evaluated where it stands errs by at most the
// irradiance the region can deliver at any point of the node (the link's value and its
// estimate both lie between 0 and that bound):
//
//   bound = B_max x min(2, A / (pi d^2))
//
// B_max: the region's largest unshot radiosity (luminance), A: its area, d: the gap
// between the node's and the region's bounding spheres (d <= 0: they touch, and only the
// solid-angle bound holds: |E| <= B_max x projected solid angle / pi <= 2 B_max over the
// receiver's half-space). The visibility is not known when the link is decided, so its
// uncertainty is taken as 1.
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

#include <cstddef>
#include <vector>

namespace mebake::solve {

class ChartField;

// Upper bound on |E| an emitter region of largest radiosity db_max and area `area` gives
// at any point whose bounding sphere is `gap` away from the region's (<= 0: touching).
double LinkIrradianceBound(double db_max, double area, double gap);

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

private:
    std::vector<float> allowed_;
};

}  // namespace mebake::solve
