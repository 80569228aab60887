// An independent reference for the baked lighting: a plain, unbiased Monte Carlo path
// tracer (Kajiya 1986, "The Rendering Equation"; next-event estimation and Russian roulette
// as in Veach's thesis, 1997, ch. 10) on the full-resolution mesh of a bake directory's
// tiles, with Embree for the rays. It estimates, at surface points chosen at random
// (area-weighted), the two quantities the light map holds:
//   radiosity          B(x) = pi Le(x) + rho(x) I(x),  I = integral over the hemisphere of the
//                      shading normal n of L_in(x, w) (n . w) dw,
//   vector irradiance  E(x) = integral over the hemisphere of the geometric normal of
//                      L_in(x, w) w dw,
// with their standard errors. It shares no code with the solver (no field, basis,
// quadrature, direct light or shooting): only the scene's definitions (materials,
// polygon lights, sky) and the Embree wrapper. Physics, stated once (docs/accuracy.md):
// surfaces are one-sided Lambertian reflectors (the back of a triangle is black, as in the
// solver's transport kernel), emitters emit from their front only, polygon lights do not
// block light, the sky is zero below its horizon, shading normals are the interpolated
// vertex normals and light below a triangle's own plane is blocked.
//
// Determinism: sample s of point i draws from its own random stream hash(seed, i, s), and
// every point accumulates its samples in order, so the result does not depend on the thread
// count. Progressive: every point starts with `min_samples`; rounds double the samples of
// the points whose standard error is still above the target, up to `max_samples`.
#pragma once

#include "core/vec.h"
#include "solve/scene.h"
#include "solve/visibility.h"
#include "stream/bake_dir.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace mebake::reference {

// The triangles of all tiles, in chart order, with what shading needs per vertex.
struct ReferenceMesh {
    std::vector<Vec3f> position, normal;
    std::vector<Vec3f> color;  // sRGB [0,1]; x < 0 = none (empty when no tile has colours)
    std::vector<Vec2f> uv;     // chart coordinates
    std::vector<std::array<uint32_t, 3>> triangles;
    std::vector<uint32_t> material;        // packed material id per triangle
    std::vector<uint32_t> chart;           // per triangle
    std::vector<uint32_t> local_triangle;  // index within its chart's tile
    std::vector<uint64_t> face_id;         // input triangle per triangle (kNoId: hole fill)
    std::vector<uint64_t> vertex_id;       // input vertex per vertex (kNoId: added by repair)
};

// Reads every tile's mesh. Throws Error(Corrupt) naming the tile on malformed tiles.
ReferenceMesh LoadReferenceMesh(const std::string& dir, const stream::Manifest& manifest);

struct ReferenceOptions {
    uint64_t seed = 1;
    uint64_t min_samples = 256;
    uint64_t max_samples = 1 << 16;
    // A point is done when the standard error of B (Euclidean over the colours) is at most
    // target x max(|B|, floor), floor = `floor_fraction` x the RMS of |B| over all points
    // (so dark points, which weigh little in a relative RMS, do not take all the time).
    double target_relative_error = 0.01;
    double floor_fraction = 0.25;
    double time_limit = 0;   // seconds; 0 = none (checked between rounds)
    int roulette_depth = 3;  // bounces before Russian roulette starts
    int max_depth = 256;     // hard cap; the throughput left there is < 0.95^253
};

struct ReferencePoint {
    // Where: the triangle of the mesh, barycentrics, and the same point as a chart point.
    uint32_t triangle = 0, chart = 0, local_triangle = 0;
    Vec3f barycentric{};
    uint64_t face_id = 0;                  // input triangle (to map into other tools' outputs)
    std::array<uint64_t, 3> vertex_ids{};  // input vertices of the corners, in barycentric order
    Vec2f uv{};
    Vec3d position{}, normal{}, geometric_normal{};
    Vec3d albedo{}, emission{};  // linear; emission is radiance Le
    // Estimates (per colour) and their standard errors.
    Vec3d b{}, b_se{};
    std::array<Vec3d, 3> e{}, e_se{};  // e[c] = vector irradiance of colour c
    uint64_t samples = 0;
    // Random stream of the point's paths: its index in the vector given to Estimate, unless
    // set (a picture's points use their pixel's index, reference_image.h).
    uint64_t stream = kIndexStream;
    static constexpr uint64_t kIndexStream = ~uint64_t(0);
};

// The point of triangle t (of mesh) at barycentrics b, with what the estimator needs.
ReferencePoint PointAt(const ReferenceMesh& mesh, const solve::Scene& scene, uint32_t t,
                       const double b[3]);

// n points, area-weighted over all triangles, deterministic for (mesh, seed).
std::vector<ReferencePoint> ChooseReferencePoints(const ReferenceMesh& mesh, const solve::Scene& scene,
                                                  int n, uint64_t seed);

struct ReferenceStats {
    int rounds = 0;
    uint64_t paths = 0, rays = 0;
    uint64_t converged = 0;  // points whose standard error met the target
    double seconds = 0;
    std::string stop;  // "converged", "max_samples" or "time_limit"
};

class ReferenceTracer {
public:
    // Keeps references to mesh and scene; builds the Embree scene.
    ReferenceTracer(const ReferenceMesh& mesh, const solve::Scene& scene);
    ~ReferenceTracer();

    // Estimates B and E at the points (their place fields must be set, e.g. by
    // ChooseReferencePoints). progress(round, converged points) is called after each round.
    ReferenceStats Estimate(std::vector<ReferencePoint>& points, const ReferenceOptions& options,
                            const std::function<void(int, uint64_t)>& progress = {}) const;

    // First hits of rays (camera rays of a reference picture) in the tracer's scene: the
    // hit's prim_id is the mesh triangle.
    void Intersect(std::span<const solve::Segment> rays, std::span<solve::Hit> hits) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace mebake::reference
