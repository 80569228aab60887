// The baked mesh with light-map uvs: every chart's triangles (hole fills included; they
// are lit like the rest) with their own vertices, so a vertex on a chart border appears
// once per chart, each copy with its chart's atlas uv. Streams tile by tile.
//
// Formats, from the file name's extension:
//   .glb  glTF 2.0 binary (io/gltf_writer.h): one primitive per atlas page (more when a
//         page exceeds 2^31 vertices), the page's tone-mapped light map embedded as PNG;
//         uvs in glTF's convention (origin top-left), TEXCOORD_0 = TEXCOORD_1 = atlas uv.
//   .ply  float x y z, nx ny nz, s t; triangles. ("-" writes PLY to stdout.)
//   .obj  v, vt, vn per vertex; triangles.
// PLY and OBJ uvs follow the bottom-left-origin convention those formats' tools use:
// (s, t) = (u, 1 - v) of the atlas uv, and with several pages the UDIM convention:
// page p is tile 1001 + p, i.e. s += p % 10, t += p / 10; the pages' files are named
// accordingly (lightmap.PagePath).
#pragma once

#include "io/gltf_writer.h"
#include "io/mesh_stream.h"
#include "output/atlas.h"
#include "output/bake_view.h"
#include "output/tonemap.h"

#include <cstdint>
#include <string>

namespace mebake::output {

struct MeshExportOptions {
    io::GlbLightMapMode glb_mode = io::GlbLightMapMode::Emissive;
    ToneMap tone;  // the light map embedded in a .glb
    io::PlyEncoding ply_encoding = io::PlyEncoding::BinaryLittleEndian;
    std::string temp_dir;  // spill files; empty: $TMPDIR or /tmp
    // The light map's pages already written as PNG with `tone` (WriteMapPages' png_path):
    // embedded as they are instead of shading and encoding the map again.
    std::vector<std::string> light_map_pngs;
};

struct MeshExportStats {
    uint64_t vertices = 0, triangles = 0;
};

// PLY/OBJ uv of chart point uv (see above).
Vec2f BottomLeftUv(const Atlas& atlas, uint32_t chart, Vec2f uv);

// Throws Error(Usage) for an unknown extension, Error(Corrupt) when tiles disagree with
// the manifest's counts.
MeshExportStats WriteBakedMesh(const BakeView& view, const Atlas& atlas, const std::string& path,
                               const MeshExportOptions& options);

}  // namespace mebake::output
