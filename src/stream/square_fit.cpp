// Unit-square placement by rotating calipers (see square_fit.h).
//
// Between two consecutive "critical" angles (hull edge directions modulo 90 degrees) the
// four extreme hull points are fixed, so the rectangle's width and height are single
// sinusoids of the angle, both concave there. The minimum of max(width, height) over such
// an interval is at an end or where width = height; the minimum of width * height is at an
// end (a side flush with an edge). The calipers advance monotonically: O(hull) overall.
#include "stream/square_fit.h"

#include "core/check.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mebake::stream {

std::vector<Vec2d> ConvexHull(std::span<const Vec2d> points) {
    std::vector<Vec2d> p(points.begin(), points.end());
    std::sort(p.begin(), p.end(), [](const Vec2d& a, const Vec2d& b) {
        return a.x < b.x || (a.x == b.x && a.y < b.y);
    });
    p.erase(std::unique(p.begin(), p.end()), p.end());
    if (p.size() < 3)
        return p;
    std::vector<Vec2d> hull(2 * p.size());
    size_t k = 0;
    for (size_t i = 0; i < p.size(); ++i) {  // lower chain
        while (k >= 2 && Cross(hull[k - 1] - hull[k - 2], p[i] - hull[k - 2]) <= 0)
            --k;
        hull[k++] = p[i];
    }
    for (size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {  // upper chain
        while (k >= lower && Cross(hull[k - 1] - hull[k - 2], p[i] - hull[k - 2]) <= 0)
            --k;
        hull[k++] = p[i];
    }
    hull.resize(k - 1);  // the last point repeats the first
    return hull;
}

namespace {

Vec2d Direction(double angle) {
    return {std::cos(angle), std::sin(angle)};
}

// Index of the hull point furthest along dir, climbing forward from `start`.
size_t Support(const std::vector<Vec2d>& hull, size_t start, const Vec2d& dir) {
    const size_t n = hull.size();
    size_t j = start;
    for (size_t steps = 0; steps < n; ++steps) {
        const size_t next = (j + 1) % n;
        if (Dot(hull[next] - hull[j], dir) <= 0)
            break;
        j = next;
    }
    return j;
}

struct Extent {
    double width, height;
};

Extent Measure(const std::vector<Vec2d>& points, double angle) {
    const Vec2d d = Direction(angle), n(-d.y, d.x);
    double lo_d = INFINITY, hi_d = -INFINITY, lo_n = INFINITY, hi_n = -INFINITY;
    for (const Vec2d& p : points) {
        lo_d = std::min(lo_d, Dot(p, d));
        hi_d = std::max(hi_d, Dot(p, d));
        lo_n = std::min(lo_n, Dot(p, n));
        hi_n = std::max(hi_n, Dot(p, n));
    }
    return {hi_d - lo_d, hi_n - lo_n};
}

double BestAngle(const std::vector<Vec2d>& hull, SquareFitObjective objective) {
    constexpr double kQuarter = std::numbers::pi / 2;
    const size_t n = hull.size();
    std::vector<double> critical;
    critical.reserve(n + 1);
    for (size_t i = 0; i < n; ++i) {
        const Vec2d e = hull[(i + 1) % n] - hull[i];
        double a = std::fmod(std::atan2(e.y, e.x), kQuarter);
        if (a < 0)
            a += kQuarter;
        critical.push_back(a);
    }
    std::sort(critical.begin(), critical.end());
    critical.erase(std::unique(critical.begin(), critical.end()), critical.end());
    critical.push_back(critical.front() + kQuarter);

    auto score = [&](double w, double h) {
        return objective == SquareFitObjective::kMinArea ? w * h : std::max(w, h);
    };
    double best_angle = critical.front(), best_score = INFINITY;
    // Caliper indices for directions d, -d, n, -n (n = d rotated by +90 degrees).
    size_t sup[4];
    {
        const double mid = 0.5 * (critical[0] + critical[1]);
        const Vec2d d = Direction(mid);
        const Vec2d dirs[4] = {d, d * -1.0, {-d.y, d.x}, {d.y, -d.x}};
        for (int k = 0; k < 4; ++k) {
            size_t arg = 0;
            for (size_t i = 1; i < n; ++i)
                if (Dot(hull[i], dirs[k]) > Dot(hull[arg], dirs[k]))
                    arg = i;
            sup[k] = arg;
        }
    }
    for (size_t k = 0; k + 1 < critical.size(); ++k) {
        const double a0 = critical[k], a1 = critical[k + 1];
        if (!(a1 > a0))
            continue;
        const Vec2d d = Direction(0.5 * (a0 + a1));
        const Vec2d dirs[4] = {d, d * -1.0, {-d.y, d.x}, {d.y, -d.x}};
        for (int c = 0; c < 4; ++c)
            sup[c] = Support(hull, sup[c], dirs[c]);
        // width(a) = W . (cos a, sin a), height(a) = H . (-sin a, cos a).
        const Vec2d w_vec = hull[sup[0]] - hull[sup[1]];
        const Vec2d h_vec = hull[sup[2]] - hull[sup[3]];
        auto width = [&](double a) {
            return Dot(w_vec, Direction(a));
        };
        auto height = [&](double a) {
            return Dot(h_vec, Vec2d(-std::sin(a), std::cos(a)));
        };
        double candidates[3] = {a0, a1, a0};
        int count = 2;
        if (objective == SquareFitObjective::kMinLongerSide) {
            // width - height = P cos a + Q sin a = 0.
            const double p = w_vec.x - h_vec.y, q = w_vec.y + h_vec.x;
            double a = std::atan2(-p, q);
            while (a < a0)
                a += std::numbers::pi;
            while (a - std::numbers::pi >= a0)
                a -= std::numbers::pi;
            if (a < a1)
                candidates[count++] = a;
        }
        for (int c = 0; c < count; ++c) {
            const double s = score(width(candidates[c]), height(candidates[c]));
            if (s < best_score) {
                best_score = s;
                best_angle = candidates[c];
            }
        }
    }
    return best_angle;
}

}  // namespace

SquareFit FitUnitSquare(std::span<const Vec2d> points, double margin,
                        SquareFitObjective objective) {
    CHECK(margin >= 0 && margin < 0.5);
    SquareFit fit;
    if (points.empty()) {
        fit.offset = Vec2d(0.5, 0.5);
        return fit;
    }
    const std::vector<Vec2d> hull = ConvexHull(points);
    double angle = 0;
    if (hull.size() >= 3) {
        angle = BestAngle(hull, objective);
    } else if (hull.size() == 2) {
        const Vec2d e = hull[1] - hull[0];
        angle = std::atan2(e.y, e.x);
    }
    fit.cos_angle = std::cos(angle);
    fit.sin_angle = std::sin(angle);
    const Extent extent = Measure(hull, angle);
    fit.width = extent.width;
    fit.height = extent.height;
    const double longer = std::max(extent.width, extent.height);
    fit.scale = longer > 0 ? (1 - 2 * margin) / longer : 1;
    // Centre the rotated bounding rectangle on (0.5, 0.5).
    double lo_x = INFINITY, hi_x = -INFINITY, lo_y = INFINITY, hi_y = -INFINITY;
    for (const Vec2d& p : hull) {
        const Vec2d q(fit.cos_angle * p.x + fit.sin_angle * p.y,
                      -fit.sin_angle * p.x + fit.cos_angle * p.y);
        lo_x = std::min(lo_x, q.x);
        hi_x = std::max(hi_x, q.x);
        lo_y = std::min(lo_y, q.y);
        hi_y = std::max(hi_y, q.y);
    }
    fit.offset =
        Vec2d(0.5 - 0.5 * (lo_x + hi_x) * fit.scale, 0.5 - 0.5 * (lo_y + hi_y) * fit.scale);
    return fit;
}

}  // namespace mebake::stream
