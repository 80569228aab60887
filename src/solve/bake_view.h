// A solved bake directory opened for output (export, render), and the shading of one chart
// from its tile at full geometric detail: every output — light maps, irradiance maps,
// per-vertex colours, rendered views, the seam metric — evaluates lighting through
// ChartShader, so they agree to the bit.
//
// ChartShader follows the seed paper's display rule B(x) = Be + rho(x) (n(x) . E(x))+ with
// n and rho from the tile's own mesh (interpolated vertex normals and colours, the
// triangle's material) and E from the chart's field at the same chart point. A point of the
// master element's virtual part takes normal, colour and material from its nearest real
// point (the seed paper's "nearest real triangle"), while E is still evaluated where the
// point is, so texels that straddle the chart's outline filter smoothly.
#pragma once

#include <span>
#include <string>

#include "core/vec.h"
#include "solve/field.h"
#include "solve/scene.h"
#include "solve/solution.h"
#include "stream/bake_dir.h"
#include "stream/tile.h"

namespace mebake::solve {

struct BakeView {
    std::string dir;
    stream::Manifest manifest;
    Scene scene;
    Solution solution;

    size_t chart_count() const { return manifest.charts.size(); }
    std::string TilePath(uint32_t chart) const { return stream::TilePath(dir, chart); }
};

// Reads the manifest, solve/solution.bin and the scene the solve used (solve/scene.json
// when the solve had one, else the inputs' materials and the default rig). Throws
// Error(Usage) when the directory is not ingested or not solved, Error(Corrupt) naming the
// file when the solution does not match the charts.
BakeView OpenBakeView(const std::string& dir);

// The resolution of every chart from the manifest, validated (Error(Corrupt) otherwise).
std::vector<uint32_t> ChartResolutions(const BakeView& view);

// What shading needs at a surface point of a chart.
struct ShadingPoint {
    Vec2f uv;                          // chart point where the field is evaluated
    Vec3f normal;                      // unit
    Vec3f albedo;                      // linear
    const Material* material = nullptr;
};

class ChartShader {
public:
    // Keeps references to tile, field and scene. Throws Error(Corrupt) naming `tile_path`
    // when a triangle's material is not in the scene.
    ChartShader(const stream::ChartTile& tile, const ChartField& field, bool radiosity_unknown,
                const Scene& scene, const std::string& tile_path);

    // The point of triangle t with barycentrics (b0, b1, b2) (they need not sum to 1
    // exactly; weights are used as given).
    ShadingPoint AtTriangle(uint32_t t, float b0, float b1, float b2) const;
    // Chart point u (clamped to the unit square), located in the chart's grid.
    ShadingPoint AtUv(Vec2f u) const;
    // Tile vertex v: its own uv, normal and colour; the material of the lowest-index
    // triangle that uses it (the default material if none does).
    ShadingPoint AtVertex(uint32_t v) const;

    // Radiosity B (W/m^2 per channel), finite and >= 0.
    Vec3f Radiosity(const ShadingPoint& p) const;
    // Radiance towards `view` (unit, surface to eye) with the glossy display approximation.
    Vec3f Glossy(const ShadingPoint& p, const Vec3f& view) const;
    // Vector irradiance E at chart point uv, per colour (zero for a radiosity solution).
    void Irradiance(Vec2f uv, Vec3f e[3]) const;

    const stream::ChartTile& tile() const { return tile_; }

private:
    Vec3f Color(uint32_t v) const;

    const stream::ChartTile& tile_;
    const ChartField& field_;
    bool radiosity_;
    const Scene& scene_;
    std::vector<uint32_t> vertex_triangle_;  // lowest triangle using each vertex
    Material default_material_;
};

}  // namespace mebake::solve
