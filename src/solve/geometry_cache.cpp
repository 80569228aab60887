#include "solve/geometry_cache.h"

#include "core/check.h"

#include <utility>

namespace mebake::solve {

GeometryPyramid::GeometryPyramid(stream::GeometryImage image)
    : owned_(std::make_shared<const stream::GeometryImage>(std::move(image))) {
    resolution = owned_->resolution;
    for (const auto& level : owned_->levels)
        levels.emplace_back(level);
}

GeometryPin GeometryPyramid::Pin() const {
    return cache_ ? cache_->Pin(chart_) : GeometryPin();
}

stream::SurfaceSample SampleBilinear(const GeometryPyramid& img, int level, float u, float v) {
    return stream::SampleBilinearOf(img, level, u, v);
}

GeometryCache::GeometryCache(const std::string& dir, uint64_t budget_bytes)
    : regions_(dir, "geometry pyramids", budget_bytes) {}

uint32_t GeometryCache::Add(const stream::GeometryImage& image) {
    CHECK(!image.levels.empty());
    Chart chart;
    chart.resolution = image.resolution;
    std::vector<std::span<const std::byte>> pieces;
    for (const auto& level : image.levels) {
        chart.level_sizes.push_back(level.size());
        pieces.push_back(std::as_bytes(std::span(level)));
    }
    const uint32_t c = regions_.Add(pieces);
    CHECK_EQ(c, charts_.size());
    charts_.push_back(std::move(chart));
    return c;
}

GeometryPyramid GeometryCache::View(uint32_t c) {
    CHECK_LT(c, charts_.size());
    GeometryPyramid p;
    p.resolution = charts_[c].resolution;
    p.cache_ = &regions_;
    p.chart_ = c;
    const auto* texels = reinterpret_cast<const stream::GeometryTexel*>(regions_.Data(c));
    for (size_t n : charts_[c].level_sizes) {
        p.levels.emplace_back(texels, n);
        texels += n;
    }
    return p;
}

}  // namespace mebake::solve
