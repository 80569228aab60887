// The bake directory (scene.mebake/): what ingest writes and every later stage reads.
//
//   manifest.json        format version, inputs, settings, counts, chart table, state
//   vertices.bin         spilled positions (Vec3f per input vertex, global order)
//   colors.bin           spilled vertex colours (RGBA8, alpha 0 = none)
//   faces.bin            spilled triangles (SpillFace)
//   owners.bin           per vertex: which brick uses it (or shared)
//   bricks/              per-brick face lists (deleted once the tiles are written)
//   tiles/cNNNNNN.tile   one chart tile per chart (chunk_file "TILE")
//   proxy.bin            the visibility mesh (chunk_file "PRXY")
//
//   solve/               the solver's outputs and checkpoints (solve/checkpoint.h)
//
// The manifest is rewritten atomically (temp + fsync + rename) after each stage, so
// it always describes files that are complete. Resume rules: docs/resume.md.
#pragma once

#include "core/vec.h"

#include <cstdint>
#include <string>
#include <vector>

namespace mebake::stream {

constexpr int kManifestVersion = 1;

struct InputRecord {
    std::string path;    // as given ("-" for stdin)
    uint64_t bytes = 0;  // bytes read
    // Identity of a file input, so a resumed bake notices a changed input: its size and
    // the CRC-32 of all its bytes (core/checksum.h); for stdin, of all the bytes that came
    // through it. hashed = false: not recorded (a directory ingested before this was
    // recorded).
    bool hashed = false;
    uint64_t file_size = 0;
    uint32_t crc32 = 0;
    uint64_t vertices = 0, triangles = 0;
    uint64_t first_vertex = 0, first_face = 0;
    bool has_colors = false;
    std::vector<std::string> materials;
    std::vector<std::string> mtllibs;
};

struct ChartRecord {
    uint32_t brick = 0;
    uint32_t triangles = 0, vertices = 0;
    uint32_t resolution = 0;      // texels per side of the chart's square
    double scale = 0;             // 3D length of the unit square's side
    double area = 0;              // real (3D) surface area
    double area_distortion = 0;   // area-weighted mean |J/J_mean - 1|
    double virtual_fraction = 0;  // part of the unit square not covered by the chart
    Vec3f bbox_min{}, bbox_max{};
};

struct Manifest {
    int version = kManifestVersion;
    std::string state;  // "spilled", "binned", "ingested"
    std::vector<InputRecord> inputs;
    // Settings that determine the tiles' bytes.
    double texel_size = 0;
    uint64_t brick_faces = 0;
    double max_distortion = 0;
    uint64_t memory_budget = 0;
    // The options it was ingested with as the user gave them ("lightmap_resolution",
    // "texel_size", "max_distortion", "memory", "format"), compared on resume.
    std::vector<std::pair<std::string, std::string>> options;
    // Counts.
    uint64_t vertex_count = 0, face_count = 0;
    Vec3d bbox_min{}, bbox_max{};
    // --ground: a ground plane was added as the last input (ground.h); the object's box is
    // the inputs' without it (the default camera and light frame the object).
    bool ground = false;
    Vec3d object_bbox_min{}, object_bbox_max{};
    // The scans' up axis: --up, else detected (up_axis.h); the default rig, camera and
    // ground stand on it. Directories from before it was recorded: +Y.
    Vec3d up{0, 1, 0};
    double surface_area = 0;
    uint32_t brick_count = 0;
    // Pass 2b (orient.h): components, those turned outwards and their triangles, and those
    // inside out but nested in another (kept). All 0 when the pass was switched off.
    struct Orientation {
        uint64_t components = 0, flipped = 0, flipped_triangles = 0, nested_kept = 0;
    } orientation;
    std::vector<ChartRecord> charts;
    uint64_t proxy_triangles = 0;
    // Largest distance of a proxy point from the input surface (0: the full mesh) and the
    // clustering cell (0: the full mesh); proxy_cluster.h.
    double proxy_deviation = 0;
    double proxy_cell_size = 0;
    // Timings of the passes, seconds.
    std::vector<std::pair<std::string, double>> timings;
};

std::string ManifestPath(const std::string& dir);
std::string TilePath(const std::string& dir, uint32_t chart);
std::string ProxyPath(const std::string& dir);

// Atomic write. Throws Error(Io).
void WriteManifest(const std::string& dir, const Manifest& m);
// Throws Error(Io) if missing, Error(Corrupt) naming the file if malformed.
Manifest ReadManifest(const std::string& dir);
bool IsBakeDirectory(const std::string& path);
// The output directory of `mebake bake` holds its bake directory as scene.mebake: that one;
// any other path as it is.
std::string BakeDirectoryIn(const std::string& path);

// Size and CRC-32 of a whole file ("-": all of stdin), read sequentially. Throws
// Error(Io) naming it.
void HashFile(const std::string& path, uint64_t* size, uint32_t* crc32);

}  // namespace mebake::stream
