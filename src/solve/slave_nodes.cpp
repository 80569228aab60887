// TieSlaveNodes (slave_nodes.h): the finer side of every coarse-fine border takes the coarser
// leaf's values at its nodes there.
#include "solve/slave_nodes.h"

#include "core/check.h"
#include "solve/basis.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace mebake::solve {
namespace {

constexpr int kMaxNodes = kMaxOrder + 1;  // nodes per axis
constexpr int kMaxBlocks = 9;

// Coefficients of the 1-D Lagrange polynomial of node a (at a/M) in the orthonormal Legendre
// basis: lagrange[a][i] = integral of l_a P~_i over [0,1], exact by the (M+1)-point rule.
std::array<std::array<double, kMaxNodes>, kMaxNodes> LagrangeToLegendre(int order) {
    std::array<std::array<double, kMaxNodes>, kMaxNodes> m{};
    const GaussRule& g = Gauss(order + 1);
    for (int p = 0; p <= order; ++p) {
        double leg[kMaxNodes];
        Legendre(order, g.x[p], leg);
        for (int a = 0; a <= order; ++a) {
            double l = 1;  // l_a(x_p)
            for (int k = 0; k <= order; ++k)
                if (k != a)
                    l *= (g.x[p] - double(k) / order) / (double(a - k) / order);
            for (int i = 0; i <= order; ++i)
                m[size_t(a)][size_t(i)] += g.w[p] * l * leg[i];
        }
    }
    return m;
}

// The coarsest leaves whose closed squares hold chart point (u, v) (the leaves at the four
// points `nudge` away diagonally, nudge smaller than any leaf), in leaf-index order (a fixed
// sum), their level, and whether a leaf finer than `own_level` holds it too.
struct Holders {
    std::array<size_t, 4> leaf{};
    int count = 0, level = 0;
    bool finer = false;
};
Holders CoarsestHolders(const ChartField& field, double u, double v, int own_level, double nudge) {
    Holders h;
    h.level = own_level;
    for (int d = 0; d < 4; ++d) {
        const double pu = u + (d & 1 ? nudge : -nudge);
        const double pv = v + (d & 2 ? nudge : -nudge);
        if (pu < 0 || pu > 1 || pv < 0 || pv > 1)
            continue;
        double s, t;
        const size_t n = field.LeafAt(pu, pv, &s, &t);
        const int nl = int(field.node(n).level);
        h.finer |= nl > own_level;
        if (nl > h.level || std::find(h.leaf.begin(), h.leaf.begin() + h.count, n) !=
                                h.leaf.begin() + h.count)
            continue;
        if (nl < h.level)
            h.count = 0;
        h.level = nl;
        h.leaf[size_t(h.count++)] = n;
    }
    for (int i = 1; i < h.count; ++i)
        for (int k = i; k > 0 && h.leaf[size_t(k)] < h.leaf[size_t(k - 1)]; --k)
            std::swap(h.leaf[size_t(k)], h.leaf[size_t(k - 1)]);
    return h;
}

}  // namespace

SlaveNodeStats TieSlaveNodes(ChartField* field, float tolerance, float floor) {
    SlaveNodeStats stats;
    const int order = field->order(), blocks = field->blocks(), m1 = order + 1;
    if (order == 0)
        return stats;
    CHECK_LE(blocks, kMaxBlocks);
    const auto lagrange = LagrangeToLegendre(order);
    double xs[kMaxNodes];
    for (int a = 0; a <= order; ++a)
        xs[a] = double(a) / order;

    std::vector<size_t> leaves;
    int deepest = 0;
    for (size_t n = 0; n < field->node_count(); ++n) {
        if (field->node(n).leaf()) {
            leaves.push_back(n);
            deepest = std::max(deepest, int(field->node(n).level));
        }
    }
    std::stable_sort(leaves.begin(), leaves.end(), [&](size_t a, size_t b) {
        return field->node(a).level < field->node(b).level;
    });
    // Smaller than any leaf: the four points this far from a node, diagonally, lie in the
    // leaves whose closed squares hold the node.
    const double nudge = std::ldexp(0.25, -deepest);

    // One coefficient set (value or unshot) of the leaves [first, last) of one level: the
    // changes of their border nodes, all computed before any is applied (leaves of the same
    // level read each other's values as they were).
    auto tie = [&](size_t first, size_t last, bool of_unshot) {
        auto coeffs = [&](size_t node) {
            return of_unshot ? field->unshot(node) : field->value(node);
        };
        std::vector<std::array<double, kMaxCoeffs * kMaxBlocks>> changes(last - first);
        std::vector<bool> changed(last - first, false);
        for (size_t q = first; q < last; ++q) {
            const size_t n = leaves[q];
            const QuadNode leaf = field->node(n);
            float own[kMaxNodes * kMaxNodes * kMaxBlocks];
            EvalTensorGrid(order, coeffs(n), blocks, xs, m1, xs, m1, own);
            auto& dc = changes[q - first];
            dc.fill(0);
            float peak = 0;
            for (int k = 0; k < m1 * m1 * blocks; ++k)
                peak = std::max(peak, std::abs(own[k]));
            bool slave = false, any = false;
            for (int c = 0; c < m1; ++c) {
                for (int a = 0; a < m1; ++a) {
                    if (a != 0 && a != order && c != 0 && c != order)
                        continue;  // interior node
                    const double u = leaf.U(xs[a]), v = leaf.V(xs[c]);
                    const Holders h = CoarsestHolders(*field, u, v, int(leaf.level), nudge);
                    // Nodes where leaves of one size meet keep their values; a node on a
                    // coarser leaf, or a corner of this one where a finer leaf hangs (other
                    // leaves of this size meeting there: their mean), is tied.
                    if (h.count == 0 || (h.level == int(leaf.level) && !h.finer))
                        continue;
                    std::array<double, kMaxBlocks> target{};  // the holders' mean
                    for (int i = 0; i < h.count; ++i) {
                        const QuadNode& hn = field->node(h.leaf[size_t(i)]);
                        float hv[kMaxBlocks];
                        EvalCoeffs(order, coeffs(h.leaf[size_t(i)]), blocks,
                                   std::clamp((u - hn.U(0)) / hn.size(), 0.0, 1.0),
                                   std::clamp((v - hn.V(0)) / hn.size(), 0.0, 1.0), hv);
                        for (int b = 0; b < blocks; ++b)
                            target[size_t(b)] += hv[b];
                    }
                    const int node = a + m1 * c;
                    slave |= h.level < int(leaf.level);
                    for (int b = 0; b < blocks; ++b) {
                        const double d = target[size_t(b)] / h.count - double(own[node * blocks + b]);
                        if (d == 0)
                            continue;
                        any = true;
                        for (int j = 0; j < m1; ++j)
                            for (int i = 0; i < m1; ++i)
                                dc[size_t(b * m1 * m1 + CoeffIndex(order, i, j))] +=
                                    d * lagrange[size_t(a)][size_t(i)] *
                                    lagrange[size_t(c)][size_t(j)];
                    }
                }
            }
            double worst = 0;
            for (int b = 0; b < blocks; ++b) {
                double norm2 = 0;  // orthonormal basis: the L2 norm of the change
                for (int k = 0; k < m1 * m1; ++k)
                    norm2 += dc[size_t(b * m1 * m1 + k)] * dc[size_t(b * m1 * m1 + k)];
                worst = std::max(worst, norm2);
            }
            // The tie may move the leaf by the tolerance in L2 (seed 002's measure for
            // a simplification); a larger change is a jump of the light itself (a contact
            // line or shadow edge along the border, inside a leaf at the depth cap or at
            // the edge of a coarser leaf the light-penumbra test does not sample there):
            // the leaf keeps its own fit.
            if (std::sqrt(worst) > tolerance * std::max(double(peak), double(floor))) {
                stats.kept_jumps += of_unshot ? 0 : 1;
                continue;
            }
            changed[q - first] = any;
            if (of_unshot)
                continue;
            stats.slaves += slave ? 1 : 0;
            if (peak > 0)
                stats.largest_change = std::max(stats.largest_change, float(std::sqrt(worst) / peak));
        }
        for (size_t q = first; q < last; ++q) {
            if (!changed[q - first])
                continue;
            float* out = coeffs(leaves[q]);
            for (int k = 0; k < m1 * m1 * blocks; ++k)
                out[k] = float(double(out[k]) + changes[q - first][size_t(k)]);
        }
    };
    for (size_t first = 0; first < leaves.size();) {
        size_t last = first;
        while (last < leaves.size() && field->node(leaves[last]).level == field->node(leaves[first]).level)
            ++last;
        tie(first, last, false);
        if (field->has_unshot())
            tie(first, last, true);
        first = last;
    }
    stats.leaves = leaves.size();
    return stats;
}

}  // namespace mebake::solve
