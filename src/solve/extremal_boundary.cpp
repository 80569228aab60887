// ExtremalBoundaries: per light, a breadth-first classification of the chart's quadtree
// (seed 002, extremal boundaries; see extremal_boundary.h). Samples sit on a lattice of
// 2^(max_level+1) cells per side, so neighbours, parents and children share them; each is
// classified once, and all new samples of a level go to the rays in one batch.
#include "solve/extremal_boundary.h"

#include "core/check.h"
#include "solve/rays.h"
#include "solve/visibility.h"

#include <algorithm>

namespace mebake::solve {

// Classification rays only: the light's vertices (pulled 1 % inward) and its centre.
void DirectLight::ClassifyPoints(size_t light, std::span<const ReceiverPoint> points,
                                 std::vector<uint8_t>* kind) const {
    const Light& l = lights_[light];
    const size_t nk = l.classify.size();
    kind->assign(points.size(), kPointAway);
    SegmentBatch batch;
    std::vector<size_t> owner;
    const std::vector<ReceiverPoint> on_surface = OnSurface(points);  // as Evaluate
    for (size_t p = 0; p < points.size(); ++p) {
        if (!Faces(l, points[p]))
            continue;
        const Vec3f o = on_surface[p].vis_point + points[p].normal * offset_;
        for (size_t k = 0; k < nk; ++k) {
            batch.AddSegment(o, l.classify[k]);
            owner.push_back(p);
        }
    }
    batch.Trace(vis_, RayKind::kClassify);
    std::vector<uint32_t> visible(points.size(), 0), traced(points.size(), 0);
    for (size_t r = 0; r < owner.size(); ++r) {
        ++traced[owner[r]];
        visible[owner[r]] += batch.occluded[r] ? 0 : 1;
    }
    for (size_t p = 0; p < points.size(); ++p) {
        if (traced[p] == 0)
            continue;
        (*kind)[p] = visible[p] == traced[p] ? kPointLit
                     : visible[p] == 0       ? kPointUmbra
                                             : kPointPenumbra;
    }
}

ExtremalBoundaries::ExtremalBoundaries(const DirectLight& direct, const SampleFn& sample,
                                       int min_level, int max_level)
    : min_level_(std::min(min_level, max_level)),
      max_level_(max_level),
      regions_(direct.light_count()),
      lookup_(direct.light_count()) {
    CHECK_LE(max_level, 27);
    for (size_t l = 0; l < direct.light_count(); ++l)
        ClassifyLight(l, direct, sample);
}

void ExtremalBoundaries::ClassifyLight(size_t light, const DirectLight& direct,
                                       const SampleFn& sample) {
    const int lattice = max_level_ + 1;          // sample lattice level
    std::unordered_map<uint64_t, uint8_t> seen;  // lattice point -> point class
    std::vector<QuadNode> level_nodes(1), next;
    for (int level = 0; !level_nodes.empty(); ++level) {
        // The 3 x 3 samples of every node of this level, new ones classified in one batch.
        const uint32_t step = 1u << (lattice - level - 1);  // half a node, in lattice units
        std::vector<uint64_t> keys;
        std::vector<ReceiverPoint> pts;
        auto lattice_key = [&](const QuadNode& n, int a, int b) {
            return Key(0, n.i * 2 * step + uint32_t(a) * step, n.j * 2 * step + uint32_t(b) * step);
        };
        for (const QuadNode& n : level_nodes) {
            for (int b = 0; b < 3; ++b) {
                for (int a = 0; a < 3; ++a) {
                    const uint64_t k = lattice_key(n, a, b);
                    if (!seen.emplace(k, 0).second)
                        continue;
                    keys.push_back(k);
                    pts.push_back(sample(float(n.U(a * 0.5)), float(n.V(b * 0.5))));
                }
            }
        }
        std::vector<uint8_t> kind;
        direct.ClassifyPoints(light, pts, &kind);
        for (size_t p = 0; p < keys.size(); ++p)
            seen[keys[p]] = kind[p];
        sample_points_ += pts.size();
        next.clear();
        for (const QuadNode& n : level_nodes) {
            bool lit = false, umbra = false, pen = false, all_pen = true;
            for (int b = 0; b < 3; ++b) {
                for (int a = 0; a < 3; ++a) {
                    const uint8_t c = seen[lattice_key(n, a, b)];
                    lit |= c == DirectLight::kPointLit;
                    umbra |= c == DirectLight::kPointUmbra;
                    pen |= c == DirectLight::kPointPenumbra;
                    all_pen &= c == DirectLight::kPointPenumbra;
                }
            }
            // Away points (the light cannot reach them) agree with lit and umbra alike.
            Class cls = kUnresolved;
            if (level >= min_level_) {
                if (!pen && !(lit && umbra))
                    cls = lit ? kLit : kUmbra;
                else if (all_pen || level >= max_level_)
                    cls = kPenumbra;
            }
            if (cls != kUnresolved) {
                regions_[light].push_back({uint8_t(level), n.i, n.j, cls});
                lookup_[light].emplace(Key(level, n.i, n.j), cls);
                continue;
            }
            for (uint32_t c = 0; c < 4; ++c) {
                QuadNode child;
                child.level = uint8_t(level + 1);
                child.i = 2 * n.i + (c & 1);
                child.j = 2 * n.j + (c >> 1);
                next.push_back(child);
            }
        }
        level_nodes.swap(next);
    }
}

ExtremalBoundaries::Class ExtremalBoundaries::ClassOf(size_t light, const QuadNode& node) const {
    const auto& map = lookup_[light];
    for (int level = int(node.level); level >= 0; --level) {
        const int d = int(node.level) - level;
        auto it = map.find(Key(level, node.i >> d, node.j >> d));
        if (it != map.end())
            return it->second;
    }
    return kUnresolved;
}

void ExtremalBoundaries::Known(const QuadNode& node, std::vector<uint8_t>* known) const {
    known->assign(regions_.size(), 0);
    for (size_t l = 0; l < regions_.size(); ++l) {
        const Class c = ClassOf(l, node);
        (*known)[l] = c == kLit ? 2 : c == kUmbra ? 3 : 0;
    }
}

}  // namespace mebake::solve
