// The solved lighting of a bake directory: solve/solution.bin (chunk_file "SOLN"), one
// quadtree with its coefficients per chart. Export and render read it with the tiles.
#pragma once

#include <string>
#include <vector>

#include "solve/field.h"

namespace mebake::solve {

constexpr uint32_t kSolutionVersion = 1;

std::string SolutionPath(const std::string& dir);

// Writes order, blocks and every chart's nodes and values (not the unshot residual).
void WriteSolution(const std::string& path, const std::vector<ChartField>& fields, bool radiosity);

struct Solution {
    bool radiosity = false;
    std::vector<ChartField> fields;
};
// Throws Error(Corrupt) naming the file on any inconsistency.
Solution ReadSolution(const std::string& path);

}  // namespace mebake::solve
