// What is lit and by what: materials per face group, emitters and the sky, and the
// solver settings — from a scene file (JSON, docs/scene-format.md), from the inputs'
// OBJ/MTL materials (Kd albedo, Ke emission), or from the default rig.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/vec.h"
#include "stream/bake_dir.h"

namespace mebake::solve {

struct Material {
    std::string name;
    Vec3f albedo{0.7f, 0.7f, 0.7f};   // diffuse reflectance, linear RGB
    bool use_vertex_colors = true;     // multiply by the scan's vertex colours if present
    float color_factor = 1.0f;         // scales vertex colours (sRGB-decoded) into albedo
    Vec3f emission{0, 0, 0};           // emitted radiance, linear RGB
    float glossy_exponent = 0;         // Phong-like lobe for display (0: diffuse)
    float glossy_weight = 0;           // share of reflectance in the glossy lobe

    bool emissive() const { return emission.x > 0 || emission.y > 0 || emission.z > 0; }
};

struct PolygonLight {
    std::vector<Vec3d> vertices;  // planar, counter-clockwise seen from the emitting side
    Vec3d radiance{0, 0, 0};      // W / (m^2 sr) per channel
    bool two_sided = false;
};

struct Sky {
    enum class Type { None, Uniform, Overcast };
    Type type = Type::None;
    Vec3d radiance{0, 0, 0};      // uniform radiance, or zenith radiance for CIE overcast
    Vec3d up{0, 1, 0};
};

// Radiance the sky sends back along a ray leaving in direction dir (any length): uniform,
// or CIE overcast L = Lz (1 + 2 cos theta) / 3 with the horizon's value below the horizon
// (what a view shows of it; the solver's and the path tracer's light has no ground part).
Vec3f SkyRadiance(const Sky& sky, const Vec3f& dir);

struct SolverSettings {
    int order = 2;                // wavelet order M: 0 constant ... 3 cubic
    double tolerance = 0.02;      // relative error that triggers subdivision
    int max_bounces = 16;         // batches of shooting after the direct pass
    // Stop when unshot power < this x emitted power (1e-3 before session 21, without the
    // tail below: 2.5e-3 with it is as accurate on every shared scan, lucy -1 batch).
    double stop_fraction = 2.5e-3;
    // At that stop, every node's value also takes its unshot coefficients x r / (1 - r), r
    // its chart's received power in the last batch against the one before: the bounces
    // left, as the last one's light (Solver::AddUnshotTail; docs/method.md, "The unshot
    // tail"; false: before session 21).
    bool unshot_tail = true;
    // ... and no chart's unshot power is this x its own reflected power (0: off, the
    // default: 0.01 converges narrow folds for +10 % of the horse's solve CPU)
    double chart_stop_fraction = 0;
    double time_limit = 0;        // seconds; 0 = none
    int sky_directions = 128;     // visibility directions per receiver point for the sky
    int light_samples = 64;       // visibility samples per receiver point in penumbrae
    bool radiosity = false;       // solve for B instead of E (for comparison, seed Table 1)
    // Direct light from several polygon lights: false = every light traced at every point
    // (full), true = extremal boundaries and the L2 simplification of seed 002 (simplify,
    // the default: the same as full with one light; docs/method.md, "Several sources").
    bool multi_emitter_simplify = true;
    bool cluster_links = true;    // far receivers through cluster links (cluster_links.cpp)
    double link_tolerance = 1;    // error-driven link refinement (link_refine.h); 0: off
    // A link whose spheres are apart errs by about link_size_error x (size / gap)^2 of its
    // bound (the point samples of its kernel), so it also stops where that share of the
    // bound is within the allowance, from the second batch on (Gatherer::Shoot; 0: off, the
    // bound itself as before session 18). 0.08 ~ 1 / (4 pi), the near form's own bound.
    double link_size_error = 0.08;
    // The sky's refinement below its gathering level (Solver::GatherSky): at most this many
    // levels deeper, and only where its fit misses by more than sky_fit_floor sky
    // directions' shares of E as well as by the tolerance (0: the tolerance alone).
    // 4 and 4 since session 18 (before: 2 and 0; docs/method.md, "Sky").
    int sky_extra_levels = 4;
    double sky_fit_floor = 4;
    // The finest emitter samples (Solver::EmitterTop): at most this many light-map texels a
    // side on charts larger than 32 x 32 of them (a power of two; 0: 32 x 32 per chart
    // whatever its size).
    int emitter_texels = 0;
    // A receiver point closer than near_emitter_split x the width of its finest emitter
    // sample takes that sample's four children (one level finer, their own radiosity and
    // rays) instead of the sample (Solver::Gatherer::CollectPairs); 0: off. 2 is where the
    // transfer kernel's near form starts (its point form's error ~ (width / distance)^2).
    double near_emitter_split = 2;
    // Opt-in: nodes two or more levels below the sky's gathering level split only where they
    // miss by more than sky_deep_floor shares, doubled per level deeper (0: sky_fit_floor).
    double sky_deep_floor = 0;
    // A virtual receiver point's face plane (DirectLight::OnSurface) is its chart's real
    // edge just inside the outline, not whichever face a ray at the outline meets (false:
    // before session 16).
    bool outline_face_inside = true;
    // The children of a node one level above the direct light's depth cap take, at their
    // new probes, the light states its four probes agreed on, without a ray, as its other
    // points did (Solver::FitDirectLights; false: before session 19, every probe traces).
    bool light_probes_inherit = true;
};

struct Scene {
    // Material of every packed material id (input << 16 | local), via MaterialOf().
    std::vector<std::vector<Material>> per_input;  // [input][local material]
    std::vector<PolygonLight> lights;
    Sky sky;
    SolverSettings solver;
    std::string description;      // where it came from, for logs and stats

    const Material& MaterialOf(uint32_t packed) const {
        return per_input[packed >> 16][packed & 0xFFFF];
    }
};

// scene_file empty: OBJ/MTL materials plus the default rig (a sky and a key area light
// placed from the bounding box). Throws Error(Input) naming the file and the field.
Scene LoadScene(const stream::Manifest& manifest, const std::string& scene_file);

// The default rig for a scene with this bounding box (exposed for tests and docs).
void AddDefaultRig(Scene& scene, const Vec3d& bbox_min, const Vec3d& bbox_max);

}  // namespace mebake::solve
