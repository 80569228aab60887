// The extremal shadow boundaries of each polygon light on one chart (seed 002, "extremal
// boundaries": the maximal boundary between penumbra and light, the minimal one between
// umbra and penumbra, found without the discontinuities inside the penumbra). A cheap
// first pass per light: quadtree nodes of the chart's square are classified from sample
// points (corners, edge midpoints, centre) by the visibility of the light's vertices and
// centre (DirectLight::ClassifyPoints). A node whose samples agree (all lit, all umbra) is
// a lit or umbra region; one whose samples are all in penumbra is penumbra interior and is
// not split further; a node whose samples disagree straddles a boundary and is split down
// to the finest level. What is exact and what is estimated: docs/method.md, "Several sources".
#pragma once

#include "solve/direct.h"
#include "solve/field.h"

#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

namespace mebake::solve {

class ExtremalBoundaries {
public:
    // Region classes; kUnresolved for a node coarser than the classification.
    enum Class : uint8_t { kUnresolved = 0, kLit = 2, kUmbra = 3, kPenumbra = 4 };
    struct Region {
        uint8_t level;
        uint32_t i, j;  // QuadNode convention
        Class cls;
    };
    // The receiver point at chart coordinates (u, v).
    using SampleFn = std::function<ReceiverPoint(float u, float v)>;

    // Classifies every light of `direct`: regions are at least min_level deep (the sampling
    // density below which a uniform node is not believed) and at most max_level.
    ExtremalBoundaries(const DirectLight& direct, const SampleFn& sample, int min_level,
                       int max_level);

    // Per light, what DirectLight::Evaluate may take as known over `node`: 2 (lit), 3
    // (umbra) where the node lies inside a lit or umbra region, else 0.
    void Known(const QuadNode& node, std::vector<uint8_t>* known) const;
    Class ClassOf(size_t light, const QuadNode& node) const;

    size_t light_count() const { return regions_.size(); }
    const std::vector<Region>& regions(size_t light) const { return regions_[light]; }
    size_t sample_points() const { return sample_points_; }

private:
    void ClassifyLight(size_t light, const DirectLight& direct, const SampleFn& sample);
    static uint64_t Key(int level, uint32_t i, uint32_t j) {
        return (uint64_t(level) << 58) | (uint64_t(i) << 29) | uint64_t(j);
    }

    int min_level_, max_level_;
    std::vector<std::vector<Region>> regions_;                 // leaves, per light
    std::vector<std::unordered_map<uint64_t, Class>> lookup_;  // leaf key -> class
    size_t sample_points_ = 0;
};

}  // namespace mebake::solve
