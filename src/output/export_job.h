// `mebake export` and `mebake render` as library calls: a solved bake directory in, the
// chosen outputs out, with the atlas, the statistics JSON and the log lines. The CLI only
// parses options into these structs.
#pragma once

#include "core/vec.h"
#include "io/gltf_writer.h"
#include "output/atlas.h"
#include "output/lightmap.h"
#include "output/render.h"
#include "output/tonemap.h"

#include <optional>
#include <string>

namespace mebake::output {

struct ExportJobOptions {
    std::string dir;  // solved bake directory
    // Outputs; empty: not written. "-" is stdout (at most one).
    std::string lightmap, irradiance, mesh, vertex_colors, stats;
    // With an .exr lightmap: its PNG from the same texels, also embedded in a .glb mesh
    // (the bake's outputs: the light map shaded and stitched once for all three).
    std::string lightmap_png;
    AtlasOptions atlas;
    MapWriteOptions maps;    // EXR pixel type and compression; maps.tone for every output
    std::string tone_curve;  // its name, for the statistics
    io::GlbLightMapMode glb_mode = io::GlbLightMapMode::Emissive;
    bool float_colors = false;  // PLY vertex colours as linear floats
    bool stitch = true;         // fields stitched across chart borders (seam_graph.h)
    bool force = false;         // overwrite existing outputs
    uint64_t memory = uint64_t(1) << 30;  // the budget (--memory): the vertex colours' and stitch caches
};

// Throws Error(Usage) when nothing is asked for, when two outputs go to stdout, or when an
// output exists and force is not set (checked before anything is written).
void RunExportJob(const ExportJobOptions& opt);

struct RenderJobOptions {
    std::string dir;
    std::string output;  // .exr (linear radiance) or .png (tone-mapped); "-" = EXR
    int width = 800, height = 600;
    double fov = 50;
    std::optional<Vec3d> eye, target, up;  // unset: the default camera's
    bool glossy = false;
    int samples = 1;
    std::optional<Vec3f> background;  // unset: the scene's sky
    ToneMap tone;
    io::ExrPixelType exr_type = io::ExrPixelType::Half;
    bool stitch = true;  // fields stitched across chart borders (seam_graph.h)
    bool force = false;
};

void RunRenderJob(const RenderJobOptions& opt);

}  // namespace mebake::output
