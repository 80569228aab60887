// Hole filling by greedy edge insertion, after the Master-Element paper ("Master-Element
// vector irradiance for large tessellated models", seeds/000, section 3.1 step 1):
// "To fill a hole, edges are iteratively inserted. Each new edge connects the pair of
// vertices (p_i, p_j) that maximizes the ratio (s_i - s_j) / d(p_i, p_j), where d is the 3D
// Euclidean distance and s a curvilinear coordinate measured along the border."
//
// Interpretation. The border is closed, so s_i - s_j depends on where s starts; we take the
// border length between p_i and p_j along the shorter of the two arcs, which does not. The
// ratio is then >= 1 and measures how much border a chord short-cuts per unit of its own
// length: sharp ears and narrow necks are closed first, wide flat stretches last. Each
// inserted chord splits the polygon into two; each piece is a hole of its own whose border
// is its own perimeter (old border edges plus the chords bounding it), and the rule is
// applied again until only triangles remain. No vertex is added.
//
// A chord is rejected when it would duplicate an edge (the mesh's, via chord_allowed, or a
// chord already inserted), when its length is zero (two copies of one point), or when it
// would cut off a degenerate triangle. Ties go to the first pair in (i, j) order. The cost
// is O(n^3) for a loop of n vertices; callers bound n.
#include "stream/hole_fill.h"

#include "core/check.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace mebake::stream {
namespace {

bool DegenerateTriangle(const Vec3d& a, const Vec3d& b, const Vec3d& c, double min_area_ratio) {
    const double twice_area = Length(Cross(b - a, c - a));
    const double longest = std::max({Dot(b - a, b - a), Dot(c - b, c - b), Dot(a - c, a - c)});
    return !(twice_area > min_area_ratio * longest);  // also catches NaN
}

}  // namespace

bool TriangulateHole(const std::vector<Vec3d>& loop,
                     const std::function<bool(uint32_t, uint32_t)>& chord_allowed,
                     double min_area_ratio, std::vector<std::array<uint32_t, 3>>* triangles) {
    const size_t n = loop.size();
    if (n < 3)
        return false;
    std::vector<std::array<uint32_t, 3>> result;
    result.reserve(n - 2);
    std::vector<std::pair<uint32_t, uint32_t>> chords;  // inserted so far, (min, max)
    auto key = [](uint32_t a, uint32_t b) {
        return std::pair(std::min(a, b), std::max(a, b));
    };
    auto chord_used = [&](uint32_t a, uint32_t b) {
        return std::find(chords.begin(), chords.end(), key(a, b)) != chords.end();
    };

    std::vector<std::vector<uint32_t>> pending;
    pending.emplace_back(n);
    for (uint32_t i = 0; i < n; ++i)
        pending[0][i] = i;
    std::vector<double> s;
    while (!pending.empty()) {
        std::vector<uint32_t> q = std::move(pending.back());
        pending.pop_back();
        const size_t m = q.size();
        if (m == 3) {
            if (DegenerateTriangle(loop[q[0]], loop[q[1]], loop[q[2]], min_area_ratio))
                return false;
            result.push_back({q[0], q[1], q[2]});
            continue;
        }
        // Curvilinear abscissa along this polygon's border.
        s.assign(m, 0.0);
        for (size_t i = 1; i < m; ++i)
            s[i] = s[i - 1] + Length(loop[q[i]] - loop[q[i - 1]]);
        const double perimeter = s[m - 1] + Length(loop[q[0]] - loop[q[m - 1]]);
        const double min_chord = 1e-9 * perimeter;

        double best = -1.0;
        size_t best_a = 0, best_b = 0;
        for (size_t a = 0; a + 2 < m; ++a) {
            for (size_t b = a + 2; b < m; ++b) {
                if (a == 0 && b == m - 1)
                    continue;  // a border edge, not a chord
                const double d = Length(loop[q[b]] - loop[q[a]]);
                if (!(d > min_chord))
                    continue;
                const double arc = s[b] - s[a];
                const double ratio = std::min(arc, perimeter - arc) / d;
                if (!(ratio > best))
                    continue;
                if (b - a == 2 &&
                    DegenerateTriangle(loop[q[a]], loop[q[a + 1]], loop[q[b]], min_area_ratio))
                    continue;
                if (m - (b - a) == 2 && DegenerateTriangle(loop[q[b]], loop[q[(b + 1) % m]],
                                                           loop[q[a]], min_area_ratio))
                    continue;
                if (chord_used(q[a], q[b]) || !chord_allowed(q[a], q[b]))
                    continue;
                best = ratio;
                best_a = a;
                best_b = b;
            }
        }
        if (best < 0)
            return false;
        chords.push_back(key(q[best_a], q[best_b]));
        std::vector<uint32_t> left(q.begin() + long(best_a), q.begin() + long(best_b) + 1);
        std::vector<uint32_t> right(q.begin() + long(best_b), q.end());
        right.insert(right.end(), q.begin(), q.begin() + long(best_a) + 1);
        pending.push_back(std::move(right));
        pending.push_back(std::move(left));
    }
    CHECK_EQ(result.size(), n - 2);

    // Order the triangles breadth-first over shared chords, starting from the one on the
    // border edge (0, 1), so a half-edge mesh can take them one by one without ever having
    // two separate fans at a vertex inside the hole.
    const size_t t_count = result.size();
    auto shares_edge = [&](const std::array<uint32_t, 3>& x, const std::array<uint32_t, 3>& y) {
        int common = 0;
        for (uint32_t u : x)
            for (uint32_t v : y)
                common += u == v;
        return common == 2;
    };
    size_t first = 0;
    for (size_t t = 0; t < t_count; ++t) {
        const auto& tri = result[t];
        bool has01 = false;
        for (int k = 0; k < 3; ++k)
            has01 |= tri[k] == 0 && tri[(k + 1) % 3] == 1;
        if (has01) {
            first = t;
            break;
        }
    }
    std::vector<uint8_t> taken(t_count, 0);
    std::vector<size_t> order{first};
    taken[first] = 1;
    for (size_t head = 0; head < order.size(); ++head)
        for (size_t t = 0; t < t_count; ++t)
            if (!taken[t] && shares_edge(result[order[head]], result[t])) {
                taken[t] = 1;
                order.push_back(t);
            }
    CHECK_EQ(order.size(), t_count);
    for (size_t t : order)
        triangles->push_back(result[t]);
    return true;
}

}  // namespace mebake::stream
