// WriteMultiEmitterPng (multi_emitter_debug.h): quadtree squares painted into panels.
#include "solve/multi_emitter_debug.h"

#include "io/png_writer.h"

#include <algorithm>
#include <array>
#include <vector>

namespace mebake::solve {
namespace {

constexpr int kPanel = 256, kGap = 4, kPerRow = 4;
using Rgb = std::array<uint8_t, 3>;

class Canvas {
public:
    Canvas(int panels)
        : cols_(std::min(panels, kPerRow)),
          rows_((panels + kPerRow - 1) / kPerRow),
          width_(cols_ * (kPanel + kGap) - kGap),
          height_(rows_ * (kPanel + kGap) - kGap),
          pixels_(size_t(width_) * size_t(height_) * 3, 255) {}

    // The node's square in panel p, filled, with a black outline.
    void Square(int p, int level, uint32_t i, uint32_t j, const Rgb& fill) {
        const int x0 = (p % kPerRow) * (kPanel + kGap), y0 = (p / kPerRow) * (kPanel + kGap);
        const double size = double(kPanel) / double(1u << level);
        const int a0 = int(i * size), a1 = std::max(a0 + 1, int((i + 1) * size));
        // v grows upward in the picture (chart coordinates), rows downward.
        const int b0 = kPanel - std::max(int(j * size) + 1, int((j + 1) * size));
        const int b1 = kPanel - int(j * size);
        const bool outline = a1 - a0 >= 3;
        for (int b = b0; b < b1; ++b)
            for (int a = a0; a < a1; ++a) {
                const bool edge = outline && (a == a0 || b == b0 || a == a1 - 1 || b == b1 - 1);
                uint8_t* px = &pixels_[(size_t(y0 + b) * size_t(width_) + size_t(x0 + a)) * 3];
                for (int c = 0; c < 3; ++c)
                    px[c] = edge ? 0 : fill[size_t(c)];
            }
    }

    void Write(const std::string& path) const { io::WritePng(path, width_, height_, 3, pixels_); }

private:
    int cols_, rows_, width_, height_;
    std::vector<uint8_t> pixels_;
};

Rgb ClassColour(ExtremalBoundaries::Class c) {
    switch (c) {
    case ExtremalBoundaries::kLit:
        return {250, 215, 80};
    case ExtremalBoundaries::kUmbra:
        return {35, 40, 110};
    case ExtremalBoundaries::kPenumbra:
        return {215, 60, 45};
    default:
        return {160, 160, 160};
    }
}

Rgb TestColour(const std::unordered_map<size_t, NodeTest>& tests, size_t n) {
    auto it = tests.find(n);
    if (it == tests.end())
        return {160, 160, 160};
    switch (it->second) {
    case NodeTest::kLightLight:
        return {90, 190, 90};
    case NodeTest::kLightPenumbra:
        return {240, 150, 40};
    case NodeTest::kSingle:
        return {70, 120, 220};
    default:
        return {200, 50, 50};
    }
}

}  // namespace

void WriteMultiEmitterPng(const std::string& path, const ExtremalBoundaries& eb,
                          const ChartField& field,
                          const std::unordered_map<size_t, NodeTest>& tests) {
    const int lights = int(eb.light_count());
    Canvas canvas(lights + 1);
    for (int l = 0; l < lights; ++l)
        for (const auto& r : eb.regions(size_t(l)))
            canvas.Square(l, r.level, r.i, r.j, ClassColour(r.cls));
    for (size_t n = 0; n < field.node_count(); ++n) {
        const QuadNode& node = field.node(n);
        if (node.leaf())
            canvas.Square(lights, node.level, node.i, node.j, TestColour(tests, n));
    }
    canvas.Write(path);
}

}  // namespace mebake::solve
