// Solver checkpoints: the state of a Southwell solve at a batch boundary, so an
// interrupted `mebake solve` continues where it stopped and ends with the same bytes as an
// uninterrupted run (docs/resume.md).
//
//   solve/checkpoint.bin       newest checkpoint (chunk_file "CKPT")
//   solve/checkpoint.prev.bin  the one before, kept until the newest is durable
//
// A checkpoint holds the charts' quadtrees with their value and unshot coefficients
// (pending is zero at a boundary), the next batch, the refinement reference and the stats
// counters: its size follows the lighting (nodes), not the triangles. Writing goes
// through checkpoint.next.bin (temporary, fsync, rename), then rotates the newest to
// .prev and the next into place, then fsyncs the directory, so at every instant at least
// one complete checkpoint exists under a known name.
#pragma once

#include "solve/field.h"
#include "solve/solver.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace mebake::solve {

// 2: the unshot tail's state in the stats (session 21): shot_power, chart_kept and
// chart_received.
constexpr uint32_t kCheckpointVersion = 2;

std::string CheckpointPath(const std::string& dir);      // dir/solve/checkpoint.bin
std::string PrevCheckpointPath(const std::string& dir);  // dir/solve/checkpoint.prev.bin
std::string NextCheckpointPath(const std::string& dir);  // dir/solve/checkpoint.next.bin

// Fingerprint of what a solve's result depends on: the headers of the tiles and of the
// proxy (their table CRCs cover every chunk) and `settings`, a canonical text of the
// solver settings and the scene. Throws Error(Io) naming a missing tile.
uint64_t SolveKey(const std::string& dir, size_t charts, const std::string& settings);

struct Checkpoint {
    std::string path;  // the file it was read from
    uint64_t key = 0;
    int next_batch = 0;
    double reference = 0;
    SolveStats stats;  // counters: batches, shots, rays, seconds, powers
    std::vector<ChartField> fields;
};

// Writes the solver's state (it must stand at a batch boundary) durably; returns the
// file's size. Throws Error(Io) naming the file; the previous checkpoint stays intact.
// Test hook: MEBAKE_TEST_KILL_IN_CHECKPOINT=N[,rotate] makes the N-th checkpoint written
// by this process SIGKILL itself halfway through its data (or, with ",rotate", between
// moving the newest to .prev and the next into place).
uint64_t WriteCheckpoint(const std::string& dir, const Solver& solver, uint64_t key);

// Reads and validates one checkpoint file against the solve's key and shape. Throws
// Error(Usage) when it was made from other tiles or settings (never silently mixed),
// Error(Corrupt) / Error(Io) naming the file when it is damaged.
// With a `sink`, every chart's field goes to it as it is read (cp.fields stays empty), so
// no more than one field is held here.
using FieldSink = std::function<void(uint32_t chart, ChartField&& field)>;
Checkpoint ReadCheckpoint(const std::string& path, uint64_t key, int order, int blocks,
                          size_t charts, const FieldSink& sink = {});

// The newest valid checkpoint of `dir` (next, newest, previous: the highest batch wins).
// Damaged or truncated files are reported with a warning naming them and skipped;
// nullopt when none is usable. A key mismatch throws Error(Usage) (see ReadCheckpoint).
// Leftover temporaries of an interrupted write are removed. With a `sink`, the candidates
// are validated one field at a time, then the chosen one is read again into the sink.
std::optional<Checkpoint> LoadCheckpoint(const std::string& dir, uint64_t key, int order,
                                         int blocks, size_t charts, const FieldSink& sink = {});

bool HasCheckpoint(const std::string& dir);
void RemoveCheckpoints(const std::string& dir);

}  // namespace mebake::solve
