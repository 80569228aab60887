// What the viewer's page loads for a solved bake: the mesh in chunks of whole charts
// (web_glb.h), the light map and the three vector-irradiance maps per atlas page as
// half-float RGBA texels, and view.json tying them together (pages, chunks, the scene's
// sky, the default camera of `mebake render`).
//
// Files, in `out`:
//   view.json
//   mesh.NNN.glb          chunk NNN: about `chunk_triangles` triangles, chart by chart
//   lightmap.P.half       page P: R G B = B (W/m^2), A = 1 + the quadtree leaf level in
//                         chart squares (1 in gutters, 0 on unused texels)
//   E.x.P.half E.y.P.half E.z.P.half   page P: R G B = that component of E per colour, A = 1
// A .half file is the page's texels (rows from the top, 4 IEEE half floats each) as byte
// planes: byte k (0 low, 1 high) of channel c of texel t at (4 k + c) T + t for T texels;
// each byte then replaced by its difference from the previous one (mod 256); the whole
// zlib-compressed (RFC 1950). The browser inflates it natively and undoes the planes in one
// pass, then uploads a half-float texture. (Half-float EXR through three.js's EXRLoader,
// decoded in JavaScript, delayed the first frame by seconds: bench/RESULTS.md. The EXR
// maps remain `mebake export`'s.)
// The maps are the ones `mebake export --lightmap/--irradiance` writes (output/lightmap.h),
// split into RGBA layers; pages are at most `max_atlas` texels per side (WebGL's usual
// texture limit is 4096 to 16384).
#pragma once

#include "output/bake_view.h"

#include <cstdint>
#include <string>

namespace mebake::view {

struct WebDataOptions {
    uint32_t max_atlas = 4096;
    uint32_t gutter = 2;
    uint64_t chunk_triangles = 65536;
    bool meshopt = true;  // EXT_meshopt_compression in the chunks
};

struct WebDataStats {
    uint64_t triangles = 0, vertices = 0, chunks = 0;
    uint64_t mesh_bytes = 0;  // all chunks
    uint32_t pages = 0;
};

// A bake directory itself, or an output directory of `mebake bake` holding scene.mebake:
// the bake directory to open. Throws Error(Usage) naming `dir` when it is neither.
std::string ResolveBakeDirectory(const std::string& dir);

// Writes the viewer's data for the solved bake at `bake_dir` into `out` (created; files
// replaced). Throws what OpenBakeView throws for an unsolved or broken bake.
WebDataStats WriteWebData(const std::string& bake_dir, const std::string& out,
                          const WebDataOptions& options = {});

// True when `out` holds view.json written after the bake's solution.
bool WebDataCurrent(const std::string& bake_dir, const std::string& out);

}  // namespace mebake::view
