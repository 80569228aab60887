#include "stream/up_axis.h"

#include "core/log.h"
#include "core/paged_file.h"
#include "stream/spill.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace mebake::stream {

namespace {

constexpr int kGrid = 128;  // occupancy cells per side of a cross-section

using Point = std::array<double, 2>;

double Turn(const Point& o, const Point& a, const Point& b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

// Area of the convex hull of the points (Andrew's monotone chain).
double HullArea(std::vector<Point> p) {
    std::sort(p.begin(), p.end());
    p.erase(std::unique(p.begin(), p.end()), p.end());
    if (p.size() < 3)
        return 0;
    std::vector<Point> h(2 * p.size());
    size_t k = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        while (k >= 2 && Turn(h[k - 2], h[k - 1], p[i]) <= 0)
            --k;
        h[k++] = p[i];
    }
    for (size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && Turn(h[k - 2], h[k - 1], p[i]) <= 0)
            --k;
        h[k++] = p[i];
    }
    double area = 0;
    for (size_t i = 0; i + 1 < k; ++i)
        area += h[i][0] * h[i + 1][1] - h[i + 1][0] * h[i][1];
    return 0.5 * std::abs(area);
}

}  // namespace

UpAxis DetectUpAxis(const std::string& dir, uint64_t vertex_count, const Vec3d& bbox_min,
                    const Vec3d& bbox_max, size_t cache_bytes) {
    const Vec3d extent = bbox_max - bbox_min;
    // Direction k = 2 * axis + side: side 0 touches at the axis' minimum (up = +axis),
    // side 1 at its maximum (up = -axis).
    std::array<std::vector<uint8_t>, 6> cells;
    for (auto& c : cells)
        c.assign(size_t(kGrid) * kGrid, 0);
    DiskArray<Vec3f> vertices(Spill::VerticesPath(dir), false, cache_bytes);
    auto cell = [](double t) {
        return std::clamp(int(t * kGrid), 0, kGrid - 1);
    };
    for (uint64_t i = 0; i < vertex_count; ++i) {
        const Vec3d p(vertices.Get(i));
        if (!std::isfinite(p.x + p.y + p.z))
            continue;
        for (int axis = 0; axis < 3; ++axis) {
            const int u = (axis + 1) % 3, w = (axis + 2) % 3;
            if (!(extent[u] > 0) || !(extent[w] > 0))
                continue;
            const size_t at = size_t(cell((p[u] - bbox_min[u]) / extent[u])) * kGrid +
                              size_t(cell((p[w] - bbox_min[w]) / extent[w]));
            const double level = kContactLevel * extent[axis];
            if (p[axis] <= bbox_min[axis] + level)
                cells[size_t(2 * axis)][at] = 1;
            if (p[axis] >= bbox_max[axis] - level)
                cells[size_t(2 * axis + 1)][at] = 1;
        }
    }
    // Support ratio per direction: the hull of the occupied cells' centres in the unit square.
    std::array<double, 6> support{};
    for (size_t k = 0; k < 6; ++k) {
        std::vector<Point> points;
        for (int a = 0; a < kGrid; ++a)
            for (int b = 0; b < kGrid; ++b)
                if (cells[k][size_t(a) * kGrid + size_t(b)])
                    points.push_back({(a + 0.5) / kGrid, (b + 0.5) / kGrid});
        support[k] = HullArea(std::move(points));
    }
    const size_t best = size_t(std::max_element(support.begin(), support.end()) - support.begin());
    UpAxis out;
    out.support = support[best];
    for (size_t k = 0; k < 6; ++k)
        if (k != best)
            out.runner_up = std::max(out.runner_up, support[k]);
    if (support[best] >= kMinSupport && support[best] >= kMargin * out.runner_up) {
        out.up = Vec3d(0, 0, 0);
        out.up[int(best / 2)] = best % 2 == 0 ? 1 : -1;
        out.detected = true;
    }
    return out;
}

std::optional<Vec3d> ParseAxis(const std::string& name) {
    static const std::array<const char*, 6> names = {"x", "-x", "y", "-y", "z", "-z"};
    std::string n = name;
    if (!n.empty() && n[0] == '+')
        n.erase(0, 1);
    for (size_t k = 0; k < names.size(); ++k)
        if (n == names[k]) {
            Vec3d v(0, 0, 0);
            v[int(k / 2)] = k % 2 == 0 ? 1 : -1;
            return v;
        }
    return std::nullopt;
}

std::string AxisName(const Vec3d& axis) {
    for (int a = 0; a < 3; ++a)
        if (std::abs(axis[a]) == 1)
            return std::string(axis[a] > 0 ? "+" : "-") + "xyz"[a];
    return fmt::format("({:.3g}, {:.3g}, {:.3g})", axis.x, axis.y, axis.z);
}

}  // namespace mebake::stream
