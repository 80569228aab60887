// Per-vertex baked colour of the ORIGINAL input mesh, in the input's vertex order, as a
// streamed PLY: for meshes whose consumers want colours, not textures.
//
// B is evaluated at every tile vertex (its own uv, normal, colour, and the material of the
// lowest-index tile triangle using it) and accumulated into a disk-backed array indexed
// by global input vertex id (core/paged_file.h DiskArray, so memory does not grow with the
// mesh). A vertex that several charts share (a chart border) gets the mean of its copies,
// summed in chart order, so the result is deterministic. Input vertices no tile references
// (dropped as degenerate or unreferenced) are black.
//
// The PLY: float x y z from the bake directory's vertex spill (vertices.bin), then
//   uchar red green blue   8-bit sRGB of the tone-mapped radiance B/pi (tonemap.h), or
//   float red green blue   linear radiance B/pi * 2^exposure with `float_colors`;
// faces: the tiles' triangles as triangles of global vertex ids, tile by tile in chart
// order (not the input's face order: the face spill is gone after ingest), hole-fill
// triangles (face id kNoId) dropped. Both counts are known before the header is written,
// so the PLY streams without a spill of its own (faces are spilled once by this pass).
#pragma once

#include "io/mesh_stream.h"
#include "output/bake_view.h"
#include "output/tonemap.h"

#include <cstdint>
#include <string>

namespace mebake::output {

struct VertexColorOptions {
    ToneMap tone;
    bool float_colors = false;
    io::PlyEncoding ply_encoding = io::PlyEncoding::BinaryLittleEndian;
    std::string temp_dir;                   // spill files; empty: $TMPDIR or /tmp
    size_t cache_bytes = size_t(64) << 20;  // page cache of each disk array
};

struct VertexColorStats {
    uint64_t vertices = 0;         // written (= the input's vertex count)
    uint64_t referenced = 0;       // of them, coloured from at least one chart
    uint64_t shared = 0;           // of them, in more than one chart (averaged)
    uint64_t faces = 0;            // written
    uint64_t hole_fill_faces = 0;  // dropped
};

// Writes to `path` ("-" = stdout). Throws Error(Corrupt) when vertices.bin or a tile
// disagrees with the manifest.
VertexColorStats WriteVertexColors(const BakeView& view, const std::string& path,
                                   const VertexColorOptions& options);

}  // namespace mebake::output
