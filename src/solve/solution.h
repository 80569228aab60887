// The solved lighting of a bake directory: solve/solution.bin (chunk_file "SOLN"), one
// quadtree with its coefficients per chart. Export and render read it with the tiles.
#pragma once

#include "io/chunk_file.h"
#include "solve/field.h"

#include <span>
#include <string>
#include <vector>

namespace mebake::solve {

constexpr uint32_t kSolutionVersion = 1;

std::string SolutionPath(const std::string& dir);

// Writes order, blocks and every chart's nodes and values (not the unshot residual), and
// `key` (chunk SKEY): the fingerprint of the tiles and settings it was solved from, so a
// resumed bake can tell whether the solution still fits (checkpoint.h SolveKey).
void WriteSolution(const std::string& path, const std::vector<ChartField>& fields, bool radiosity,
                   uint64_t key = 0);
// The SKEY of a solution file; 0 when it has none. Throws like ReadSolution.
uint64_t ReadSolutionKey(const std::string& path);

// Quadtree nodes as stored on disk (no padding, so a file's bytes are fully determined).
struct PackedNode {
    int32_t first_child;
    uint32_t level, i, j;
};
std::vector<PackedNode> PackNodes(std::span<const QuadNode> nodes);
// Checks the tree structure; throws Error(Corrupt) naming `path` and the chart.
std::vector<QuadNode> UnpackNodes(const std::vector<PackedNode>& packed, const std::string& path,
                                  uint32_t chart);

struct Solution {
    bool radiosity = false;
    std::vector<ChartField> fields;
};
// Throws Error(Corrupt) naming the file on any inconsistency.
Solution ReadSolution(const std::string& path);

// One chart of a solution at a time (export holds only the charts it is writing). Read()
// may be called from several threads.
class SolutionReader {
public:
    // Reads and checks the header; throws like ReadSolution.
    explicit SolutionReader(const std::string& path);
    bool radiosity() const { return radiosity_; }
    int order() const { return order_; }
    int blocks() const { return blocks_; }
    uint32_t chart_count() const { return charts_; }
    // Chart c's field, values only; throws Error(Corrupt) naming the file and chart.
    ChartField Read(uint32_t c) const;

private:
    std::string path_;
    io::ChunkReader reader_;
    bool radiosity_ = false;
    int order_ = 0, blocks_ = 0;
    uint32_t charts_ = 0;
};

}  // namespace mebake::solve
