// The debug picture of --multi-emitter simplify on one chart (solve --multi-emitter-debug
// DIR): per light its extremal-boundary classification of the chart's square, and the final
// refinement of the direct light with how each leaf was tested. docs/method.md, "Several
// sources", explains the colours.
#pragma once

#include "solve/extremal_boundary.h"
#include "solve/field.h"

#include <cstdint>
#include <string>
#include <unordered_map>

namespace mebake::solve {

// How SimplifiedNode decided a node (kept or split after it).
enum class NodeTest : uint8_t {
    kCap,            // at the depth cap: fitted, not tested
    kLightLight,     // every light lit or in umbra: closed form, L2 test
    kLightPenumbra,  // some light in penumbra: sampled, residual test
    kSingle,         // at most one light reaches it: control grid as in full
};

// Writes `path` (PNG): one panel per light (lit yellow, umbra dark blue, penumbra red,
// unresolved grey, region borders black), then the field's leaves coloured by `tests`
// (node index -> test; light-light green, light-penumbra orange, one light blue, cap red,
// none grey),
// outlined. Panels are 256 x 256 pixels, four to a row.
void WriteMultiEmitterPng(const std::string& path, const ExtremalBoundaries& eb,
                          const ChartField& field,
                          const std::unordered_map<size_t, NodeTest>& tests);

}  // namespace mebake::solve
