// `mebake ingest`: meshes of any size, from files or a pipe, into a bake directory of
// chart tiles, in memory bounded by the budget:
//   pass 1 spill     vertices and faces to flat files (spill.h)
//   pass 2 bricks    faces binned by Morton order into bricks of at most 400K faces
//                    (bricks.h); the budget decides how many are in core at once
//   pass 2b orient   components wound inwards turned outwards (orient.h)
//   pass 3 charts    per brick in parallel: repair, charts, parameterization, tiles
//                    (chart_builder.h)
//   pass 4 proxy     the visibility mesh (proxy.bin): the full mesh, one chunk per brick,
//                    or over 64 MiB of Embree scene a clustered proxy (proxy_cluster.h)
// Nothing written depends on --memory (only how much is in core at once), so a bake
// ingested under 256M is the bytes of one under 4G.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "io/mesh_stream.h"
#include "stream/bake_dir.h"

namespace mebake::stream {

struct IngestOptions {
    std::vector<std::string> inputs;          // paths; "-" is stdin (at most once)
    std::optional<io::MeshFormat> format;     // for stdin
    std::string out_dir;
    uint64_t memory = uint64_t(1) << 30;      // the budget, bytes
    int threads = 0;                          // 0: all cores
    double texel_size = 0;                    // 0: from lightmap_resolution
    uint32_t lightmap_resolution = 2048;      // atlas side the texel size aims at
    double max_distortion = 0.05;             // Jacobian deviation that splits a chart
    bool force = false;                       // replace an existing bake directory
    bool ground = false;                      // add a ground plane under the inputs (ground.h)
    std::optional<Vec3d> up;                  // the scans' up axis; none: detected (up_axis.h)
    bool orient = true;                       // turn inside-out components outwards (orient.h)
    // The merge's turn bound on cells of 8 light-map texels (ChartBuildOptions).
    bool merge_horizon_cells = false;
    // The layout, fixed whatever `memory` (tests make them small to get many bricks or a
    // clustered proxy from a small mesh).
    uint64_t brick_faces = 400000;            // at most per brick (charts end at brick borders)
    uint64_t visibility_bytes = uint64_t(64) << 20;  // Embree scene the proxy is sized to
};

Manifest Ingest(const IngestOptions& opt);

}  // namespace mebake::stream
