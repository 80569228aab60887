// C0 continuity at T-vertices (seed 002, section 5.1: "T-vertices are treated as slave
// nodes ... the corresponding value of the neighbouring simplified interpolant replaces the
// previously assigned nodal value"). A leaf's polynomial of order M (M+1 values per axis) is
// fixed by its values at the (M+1)^2 equispaced nodes (corners and sides included), and its
// trace along a side depends on that side's M+1 nodes only. Every node on a leaf's border
// takes the value of the coarsest leaves whose closed squares hold it: where a coarser
// leaf (a simplified node) borders finer ones, those are the T-vertices, and the finer
// leaves' traces become the coarser one's restricted, continuous along the whole side, not
// only at the nodes. Where leaves of one size meet (a shared side, or a corner where two
// coarser leaves touch diagonally next to a finer one, which would otherwise get two
// values) the node takes their mean. Interior nodes keep their values. A leaf is tied only
// where that moves it by at most the tolerance (of its largest nodal value) in L2, seed
// 002's measure for a simplification; a larger change means a jump of the light itself
// along the border (a contact line or shadow edge through a leaf at the depth cap) or a
// coarser leaf whose edge its test did not sample (the light-penumbra test samples Gauss
// points only), and the leaf keeps its own fit there. --multi-emitter simplify applies it
// to the direct light (refine_direct.cpp; docs/method.md, "Several sources").
#pragma once

#include "solve/field.h"

#include <cstddef>

namespace mebake::solve {

struct SlaveNodeStats {
    size_t leaves = 0;  // leaves visited
    size_t slaves = 0;  // leaves tied with a node on a coarser leaf's side (a T-vertex)
    // Largest L2 norm (normalized node measure, worst block) of what a leaf's polynomial
    // changed by, over the leaf's largest nodal value (0 if none changed).
    float largest_change = 0;
    size_t kept_jumps = 0;  // leaves left untied: the tie would move them by more than that
};

// Ties the border nodes of every leaf (value and unshot) as above. Leaves are visited coarse
// to fine, one level at a time: a coarser leaf is final before finer ones read it, and
// leaves of one level read each other as they were (sums in leaf-index order: deterministic).
// tolerance and floor as the fit's test: the scale of a leaf is its largest nodal value, at
// least `floor`. Call ChartField::Pull() after. Order 0 has no nodes on the sides: nothing
// changes.
SlaveNodeStats TieSlaveNodes(ChartField* field, float tolerance, float floor);

}  // namespace mebake::solve
