// Exact extremal boundaries from EV events (extremal_boundary_exact.h; seed 002, 4.1).
#include "solve/extremal_boundary_exact.h"

#include "core/check.h"
#include "solve/polygon_light.h"
#include "stream/square_fit.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace mebake::solve {
namespace {

// Where the ray from l through o meets the plane, in (s, t).
Vec2d Project(const ReceiverPlane& pl, const Vec3d& l, const Vec3d& o) {
    const Vec3d n = Cross(pl.u, pl.v);
    const double hl = Dot(n, l - pl.origin), ho = Dot(n, o - pl.origin);
    CHECK_GT(hl, ho);  // the occluder lies between the light and the receiver
    const Vec3d x = l + (o - l) * (hl / (hl - ho)) - pl.origin;
    // Solve x = s u + t v (u, v need not be orthogonal).
    const double uu = Dot(pl.u, pl.u), uv = Dot(pl.u, pl.v), vv = Dot(pl.v, pl.v);
    const double xu = Dot(x, pl.u), xv = Dot(x, pl.v), det = uu * vv - uv * uv;
    return {(xu * vv - xv * uv) / det, (xv * uu - xu * uv) / det};
}

// The part of convex polygon p where a s + b t + c >= 0.
std::vector<Vec2d> ClipHalfPlane(const std::vector<Vec2d>& p, double a, double b, double c) {
    std::vector<Vec2d> out;
    for (size_t k = 0; k < p.size(); ++k) {
        const Vec2d& x = p[k];
        const Vec2d& y = p[(k + 1) % p.size()];
        const double fx = a * x.x + b * x.y + c, fy = a * y.x + b * y.y + c;
        if (fx >= 0)
            out.push_back(x);
        if ((fx > 0 && fy < 0) || (fx < 0 && fy > 0))
            out.push_back(x + (y - x) * (fx / (fx - fy)));
    }
    return out;
}

// Intersection of two counter-clockwise convex polygons.
std::vector<Vec2d> IntersectConvex(std::vector<Vec2d> p, const std::vector<Vec2d>& q) {
    for (size_t k = 0; k < q.size() && !p.empty(); ++k) {
        const Vec2d& a = q[k];
        const Vec2d& b = q[(k + 1) % q.size()];
        // Left of a -> b: cross(b - a, x - a) >= 0.
        p = ClipHalfPlane(p, -(b.y - a.y), b.x - a.x, (b.y - a.y) * a.x - (b.x - a.x) * a.y);
    }
    return p;
}

// Faces of an occluder facing point x (their outward normals towards x), by face; a single
// face (a polygon) faces both ways, so all its edges are silhouettes.
std::vector<int> Facing(const ConvexOccluder& o, const Vec3d& x, const Vec3d& centre) {
    std::vector<int> f(o.faces.size());
    for (size_t i = 0; i < o.faces.size(); ++i) {
        std::vector<Vec3d> loop;
        for (int v : o.faces[i])
            loop.push_back(o.vertices[size_t(v)]);
        Vec3d n = PolygonNormal(loop);
        if (Dot(n, loop[0] - centre) < 0)
            n = -n;  // outward
        f[i] = Dot(n, x - loop[0]) > 0 ? 1 : 0;
    }
    return f;
}

// Silhouette edges of o seen from x: edges between a face facing x and one that does not
// (every edge of a single polygon).
std::vector<std::array<int, 2>> Silhouette(const ConvexOccluder& o, const Vec3d& x) {
    if (o.faces.size() <= 1)
        return o.Edges();
    Vec3d centre{};
    for (const auto& v : o.vertices)
        centre += v;
    centre = centre / double(o.vertices.size());
    const std::vector<int> facing = Facing(o, x, centre);
    std::map<std::array<int, 2>, std::vector<int>> adjacent;
    for (size_t i = 0; i < o.faces.size(); ++i) {
        const auto& f = o.faces[i];
        for (size_t k = 0; k < f.size(); ++k) {
            const int a = f[k], b = f[(k + 1) % f.size()];
            adjacent[{std::min(a, b), std::max(a, b)}].push_back(facing[i]);
        }
    }
    std::vector<std::array<int, 2>> out;
    for (const auto& [e, fs] : adjacent)
        if (fs.size() == 2 && fs[0] != fs[1])
            out.push_back(e);
    return out;
}

bool SegmentsCross(const std::array<Vec2d, 2>& p, const std::array<Vec2d, 2>& q) {
    auto side = [](const Vec2d& a, const Vec2d& b, const Vec2d& c) {
        return Cross(b - a, c - a);
    };
    const double d1 = side(p[0], p[1], q[0]), d2 = side(p[0], p[1], q[1]);
    const double d3 = side(q[0], q[1], p[0]), d4 = side(q[0], q[1], p[1]);
    return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

}  // namespace

std::vector<std::array<int, 2>> ConvexOccluder::Edges() const {
    std::vector<std::array<int, 2>> e;
    for (const auto& f : faces)
        for (size_t k = 0; k < f.size(); ++k) {
            const int a = f[k], b = f[(k + 1) % f.size()];
            e.push_back({std::min(a, b), std::max(a, b)});
        }
    std::sort(e.begin(), e.end());
    e.erase(std::unique(e.begin(), e.end()), e.end());
    return e;
}

bool InsideConvex(std::span<const Vec2d> poly, const Vec2d& p) {
    if (poly.size() < 3)
        return false;
    for (size_t k = 0; k < poly.size(); ++k)
        if (Cross(poly[(k + 1) % poly.size()] - poly[k], p - poly[k]) < 0)
            return false;
    return true;
}

std::vector<Vec2d> SeparatingWedgeShadow(std::span<const Vec3d> light, const ConvexOccluder& occ,
                                         const ReceiverPlane& plane, size_t* wedges) {
    double extent = 1;
    for (const auto& l : light)
        for (const auto& o : occ.vertices) {
            const Vec2d p = Project(plane, l, o);
            extent = std::max({extent, std::abs(p.x), std::abs(p.y)});
        }
    const double r = 4 * extent;
    std::vector<Vec2d> shadow = {{-r, -r}, {r, -r}, {r, r}, {-r, r}};
    // The plane through p, a, b when it has the light on one side and the occluder on the
    // other: the shadow lies on the occluder's side.
    auto wedge = [&](const Vec3d& p, const Vec3d& a, const Vec3d& b) {
        Vec3d m = Cross(a - p, b - p);
        const double len = Length(m);
        if (len < 1e-14)
            return;
        m = m / len;
        double lmin = 0, lmax = 0, omin = 0, omax = 0;
        for (const auto& l : light) {
            lmin = std::min(lmin, Dot(m, l - p));
            lmax = std::max(lmax, Dot(m, l - p));
        }
        for (const auto& o : occ.vertices) {
            omin = std::min(omin, Dot(m, o - p));
            omax = std::max(omax, Dot(m, o - p));
        }
        const double eps = 1e-12 * extent;
        if (lmax <= eps && omin >= -eps && (omax > eps || lmin < -eps)) {
            // light on the negative side, occluder on the positive one
        } else if (lmin >= -eps && omax <= eps && (omin < -eps || lmax > eps)) {
            m = -m;
        } else {
            return;
        }
        ++*wedges;
        shadow = ClipHalfPlane(shadow, Dot(m, plane.u), Dot(m, plane.v), Dot(m, plane.origin - p));
    };
    const size_t nl = light.size();
    for (size_t i = 0; i < nl; ++i)
        for (const auto& e : occ.Edges())
            wedge(light[i], occ.vertices[size_t(e[0])], occ.vertices[size_t(e[1])]);
    for (const auto& o : occ.vertices)
        for (size_t i = 0; i < nl; ++i)
            wedge(o, light[i], light[(i + 1) % nl]);
    return shadow;
}

ExactExtremalBoundary::ExactExtremalBoundary(std::span<const Vec3d> light,
                                             std::span<const ConvexOccluder> occluders,
                                             const ReceiverPlane& plane) {
    for (const ConvexOccluder& occ : occluders) {
        // Maximal: the hull of every occluder vertex seen from every light vertex (the
        // polygon the separating EV wedges bound: its vertices are these projections).
        // Minimal: the occluder's shadows from each light vertex, intersected.
        std::vector<Vec2d> all, umbra;
        for (size_t i = 0; i < light.size(); ++i) {
            std::vector<Vec2d> proj;
            for (const auto& o : occ.vertices)
                proj.push_back(Project(plane, light[i], o));
            all.insert(all.end(), proj.begin(), proj.end());
            const std::vector<Vec2d> hull = stream::ConvexHull(proj);
            umbra = i == 0 ? hull : IntersectConvex(umbra, hull);
        }
        maximal_.push_back(stream::ConvexHull(all));
        minimal_.push_back(umbra.size() >= 3 ? umbra : std::vector<Vec2d>{});
    }
}

ExtremalBoundaries::Class ExactExtremalBoundary::Classify(const Vec2d& st) const {
    bool shadow = false;
    for (size_t k = 0; k < maximal_.size(); ++k) {
        if (InsideConvex(minimal_[k], st))
            return ExtremalBoundaries::kUmbra;
        shadow |= InsideConvex(maximal_[k], st);
    }
    return shadow ? ExtremalBoundaries::kPenumbra : ExtremalBoundaries::kLit;
}

DiscontinuityStructure CompleteDiscontinuities(std::span<const Vec3d> light,
                                               std::span<const ConvexOccluder> occluders,
                                               const ReceiverPlane& plane) {
    DiscontinuityStructure d;
    const size_t nl = light.size();
    for (const ConvexOccluder& occ : occluders) {
        // EV: each light vertex with the occluder's silhouette edges seen from it.
        std::vector<std::vector<std::array<int, 2>>> sil(nl);
        for (size_t i = 0; i < nl; ++i) {
            sil[i] = Silhouette(occ, light[i]);
            for (const auto& e : sil[i]) {
                ++d.wedges;
                d.segments.push_back({Project(plane, light[i], occ.vertices[size_t(e[0])]),
                                      Project(plane, light[i], occ.vertices[size_t(e[1])])});
            }
        }
        // VE: each light edge with the occluder's silhouette vertices seen from its ends.
        for (size_t i = 0; i < nl; ++i) {
            const size_t j = (i + 1) % nl;
            std::vector<int> verts;
            for (const auto* s : {&sil[i], &sil[j]})
                for (const auto& e : *s)
                    verts.insert(verts.end(), {e[0], e[1]});
            std::sort(verts.begin(), verts.end());
            verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
            for (int v : verts) {
                ++d.wedges;
                const Vec3d& o = occ.vertices[size_t(v)];
                d.segments.push_back({Project(plane, light[i], o), Project(plane, light[j], o)});
            }
        }
    }
    for (size_t a = 0; a < d.segments.size(); ++a)
        for (size_t b = a + 1; b < d.segments.size(); ++b)
            d.crossings += SegmentsCross(d.segments[a], d.segments[b]) ? 1 : 0;
    return d;
}

}  // namespace mebake::solve
