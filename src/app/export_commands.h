// `mebake export` and `mebake render` as plain functions over option structs (main.cpp,
// the only file that sees CLI11, fills them). Each returns an exit code or throws
// mebake::Error.
#pragma once

#include "core/vec.h"

#include <cstdint>
#include <string>
#include <vector>

namespace mebake::app {

// A camera or colour option's three numbers as a vector; a usage error names the option
// (render, export's views and the reference picture share the camera options).
Vec3d ToVec3(const std::vector<double>& v, const char* option);

// --memory: a size such as 512M or 2G, at least 64M (usage error otherwise).
uint64_t ParseMemory(const std::string& text);

struct ExportCommand {
    std::string dir;            // solved bake directory
    std::string lightmap;       // .exr (linear B) or .png (tone-mapped); pages get UDIM numbers
    std::string irradiance;     // .exr: vector irradiance E, 9 channels
    std::string mesh;           // .glb (light map embedded), .ply or .obj with atlas uvs
    std::string vertex_colors;  // .ply of the input mesh with baked colours, or "-"
    std::string stats;          // JSON statistics (atlas, outputs, seam metric), or "-"
    uint32_t max_atlas = 8192;  // largest atlas page side (power of two)
    uint32_t gutter = 2;        // texels around each chart
    bool npot = false;          // atlas pages of any multiple of 4 (default powers of two)
    double exposure = 0;        // EV, for tone-mapped outputs
    std::string tonemap = "filmic";   // filmic, reinhard, clamp
    bool float_output = false;        // EXR as float (not half); PLY colours as linear float
    std::string compression = "zip";  // EXR: zip, piz, none
    bool unlit = false;               // .glb: KHR_materials_unlit instead of an emissive material
    int threads = 0;
    bool force = false;      // overwrite existing outputs
    bool no_stitch = false;  // each chart's own field at chart borders
    std::string memory = "1G";  // the budget
};
int RunExport(const ExportCommand& c);

struct RenderCommand {
    std::string dir;
    std::string output;                   // .exr (linear radiance) or .png (tone-mapped); "-" = EXR
    std::vector<double> eye, target, up;  // 3 numbers each; eye empty: a default view
    double fov = 50;                      // vertical, degrees
    std::string size = "800x600";
    bool glossy = false;
    int samples = 1;                 // per pixel and axis
    std::vector<double> background;  // 3 numbers (radiance); empty: the scene's sky
    double exposure = 0;
    std::string tonemap = "filmic";
    bool float_output = false;  // EXR float instead of half
    int threads = 0;
    bool force = false;
    bool no_stitch = false;  // each chart's own field at chart borders
};
int RunRender(const RenderCommand& c);

}  // namespace mebake::app
