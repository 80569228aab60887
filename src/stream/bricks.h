// Ingest pass 2: face binning into spatial bricks.
//
// Faces are ordered by the Morton code of their centroid on a 128^3 grid over the
// scene's bounding box; a brick is a run of consecutive octree cells (a contiguous
// Morton range, hence spatially compact) holding at most `max_faces` faces, unless a
// single cell holds more. Each brick's faces go to their own file of LZ4 blocks. A
// vertex used by faces of two bricks is marked shared: boundary loops through shared
// vertices are brick cuts, not holes, and are never filled.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/progress.h"
#include "core/vec.h"
#include "stream/spill.h"
#include "stream/trimesh.h"

namespace mebake::stream {

// One face as stored in a brick file.
struct BrickFace {
    uint64_t v[3];
    uint64_t face_id;   // global triangle index (position in faces.bin)
    uint32_t material;
    uint32_t reserved;
};
static_assert(sizeof(BrickFace) == 40);

constexpr uint32_t kOwnerNone = 0xFFFFFFFFu;
constexpr uint32_t kOwnerShared = 0xFFFFFFFEu;

struct BrickInfo {
    uint64_t face_count = 0;
    uint32_t first_cell = 0, end_cell = 0;  // Morton range [first, end) at level 7
};

struct BrickPlan {
    std::vector<BrickInfo> bricks;
    double surface_area = 0;  // of all faces, for the default texel size
    uint64_t degenerate_faces = 0;  // faces repeating a vertex index (dropped here)
};

struct BinOptions {
    uint64_t max_faces = 200000;
    size_t cache_bytes = size_t(64) << 20;  // vertex look-up and owner caches
    ProgressStage* progress = nullptr;      // counts each face twice (cells, distribution)
};

// Reads the spill in `dir`, writes <dir>/bricks/bNNNNN.faces and <dir>/owners.bin
// (uint32 per vertex: brick index, kOwnerNone or kOwnerShared).
BrickPlan BinFaces(const std::string& dir, const SpillResult& spill, const BinOptions& opt);

std::string BrickPath(const std::string& dir, uint32_t brick);
std::string OwnersPath(const std::string& dir);

// Reads back one brick's faces.
std::vector<BrickFace> ReadBrick(const std::string& dir, uint32_t brick);
// Replaces one brick's file with these faces (orient.h reverses some).
void WriteBrick(const std::string& dir, uint32_t brick, const std::vector<BrickFace>& faces);

// The brick's faces as a TriMesh with local indices (global ids ascending, triangles in
// the brick file's order), its vertices' positions and colours from the spill, and per
// vertex whether faces of another brick use it too (on_cut).
TriMesh LoadBrick(const std::string& dir, uint32_t brick, size_t cache_bytes,
                  std::vector<uint8_t>* on_cut);

}  // namespace mebake::stream
