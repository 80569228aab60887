// Point-to-patch transfer of vector irradiance by quadrature over emitter samples, and a
// conservative bound of a node-to-node transfer used to pick the "suitable scale"
// (seed paper 000 section 2 transport; docs/method.md; the bound is the usual
// hierarchical-radiosity estimate F <= A cos / (pi d^2), Hanrahan et al. 1991).
//
// Transfer: dE(x) = sum_k B_k V_k max(0, (x-y_k).n_k) (y_k - x) / (pi |y_k-x|^4) w_k
// The receiver has no cosine (E is a vector field). With Kernel::kDisk the denominator
// pi r^4 becomes r^2 (pi r^2 + w_k): each sample is treated as a disc of area w_k seen
// on-axis (Wallace et al. 1989), so no sample contributes more than B_k however close x is;
// the relative change is w_k / (pi r^2), negligible at the distances quadrature is used for.
#pragma once

#include "core/vec.h"

#include <cstdint>
#include <span>

namespace mebake::solve {

// Emitter quadrature samples, structure of arrays; all spans have the same length.
struct EmitterSamples {
    std::span<const float> px, py, pz;  // positions y_k
    std::span<const float> nx, ny, nz;  // unit normals n_k (the emitting side)
    std::span<const float> weight;      // area weights w_k in world units (0 on virtual parts)
    std::span<const float> r, g, b;     // radiosity B_k per colour
    size_t size() const { return px.size(); }
};

enum class Kernel {
    kPoint,  // the exact point kernel; r^2 is floored only so that x == y_k gives no NaN
    kDisk,   // disc-regularized (default): bounded by B_k per sample
};

// Vector irradiance per colour: e[c*3 + axis], c in {r,g,b}, axis in {x,y,z}.
struct RgbVector {
    double e[9] = {};
};

// out += sum over samples as above. `visible` is V_k (0/1 per sample) or empty for "all
// visible". Summation order is fixed (independent of threads and of how callers batch).
void AccumulateTransfer(const EmitterSamples& samples, std::span<const uint8_t> visible,
                        const Vec3f& x, RgbVector* out, Kernel kernel = Kernel::kDisk);

struct BoundingSphere {
    Vec3f center;
    float radius = 0;
};

// A sphere containing all the points (centre of the bounding box, radius to the farthest).
BoundingSphere ComputeBoundingSphere(std::span<const float> px, std::span<const float> py,
                                     std::span<const float> pz);

struct TransferBound {
    double gap = 0;          // distance between the spheres; <= 0 when they overlap
    double form_factor = 0;  // bound of A_e / (pi gap^2) (>= the point-to-patch factor at any
                             // receiver point), +inf when the spheres overlap
    double e_max = 0;        // bound of |dE| at any receiver point: b_max * min(form_factor, 4)
                             // (with visibility every direction meets one emitter point, so
                             // |E| <= (B/pi) * 4 pi)
    double spread = 0;       // (r_e + r_r) / centre distance: angular size of the pair; the
                             // kernel varies over the nodes roughly in proportion to it
};

// Conservative bound for shooting from an emitter node (bounding sphere, real area, largest
// radiosity over colours and samples) to a receiver node.
TransferBound BoundTransfer(const BoundingSphere& emitter, double emitter_area, double b_max,
                            const BoundingSphere& receiver);

}  // namespace mebake::solve
