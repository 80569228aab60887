#include "view/web_data.h"

#include "core/error.h"
#include "core/log.h"
#include "io/byte_stream.h"
#include "output/atlas.h"
#include "output/lightmap.h"
#include "output/render.h"
#include "solve/solution.h"
#include "stream/bake_dir.h"
#include "view/web_glb.h"

#include <Imath/half.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <zlib.h>

namespace mebake::view {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json Vec(const Vec3d& v) {
    return {v.x, v.y, v.z};
}
json Vec(const Vec3f& v) {
    return {v.x, v.y, v.z};
}

void WriteFile(const std::string& path, std::span<const uint8_t> bytes) {
    auto out = io::OutputStream::Open(path);
    out->Write(bytes.data(), bytes.size());
    out->Commit();
}

// Alpha of the light map inside each chart square of page p: 1 + the level of the quadtree
// leaf holding the texel's centre (the page's overlay of leaves reads it back).
void MarkLeafLevels(const output::BakeView& view, const output::Atlas& atlas, uint32_t p,
                    std::vector<float>& rgba) {
    const uint32_t width = atlas.pages[p].width;
    for (uint32_t c = 0; c < atlas.charts.size(); ++c) {
        const output::AtlasChart& ac = atlas.charts[c];
        if (ac.page != p)
            continue;
        const auto field = view.Field(c);
        const uint32_t r = ac.resolution;
        for (uint32_t j = 0; j < r; ++j)
            for (uint32_t i = 0; i < r; ++i) {
                double s, t;
                const size_t leaf = field->LeafAt((i + 0.5) / r, (j + 0.5) / r, &s, &t);
                const size_t x = ac.x + atlas.gutter + i, y = ac.y + atlas.gutter + j;
                rgba[(y * width + x) * 4 + 3] = 1.f + float(field->node(leaf).level);
            }
    }
}

// RGBA floats as half-float texels in the layout of web_data.h: byte planes (low bytes of
// channel R of every texel, then of G, B, A, then the high bytes likewise), each byte
// replaced by its difference from the one before (mod 256), zlib-compressed. Smooth maps
// then give runs of small numbers (OpenEXR's ZIP does the same), and the browser undoes it
// with one pass after inflating natively (DecompressionStream).
void WriteHalfMap(const std::string& path, std::span<const float> rgba) {
    const size_t texels = rgba.size() / 4;
    std::vector<uint8_t> planes(rgba.size() * 2);
    for (size_t t = 0; t < texels; ++t)
        for (size_t c = 0; c < 4; ++c) {
            const float f = rgba[4 * t + c];
            const uint16_t h =
                imath_float_to_half(std::isfinite(f) ? std::clamp(f, -65504.f, 65504.f) : 0.f);
            planes[c * texels + t] = uint8_t(h & 0xFF);
            planes[(4 + c) * texels + t] = uint8_t(h >> 8);
        }
    for (size_t i = planes.size(); i-- > 1;)
        planes[i] = uint8_t(planes[i] - planes[i - 1]);
    const uLong raw = uLong(planes.size());
    std::vector<uint8_t> z(compressBound(raw));
    uLongf len = z.size();
    if (compress2(z.data(), &len, planes.data(), raw, 6) != Z_OK)
        IoError({path}, "zlib compression failed");
    WriteFile(path, {z.data(), size_t(len)});
}

// Page p's light map and E maps as <layer>.<p>.half (see web_data.h).
void WritePageMaps(const output::BakeView& view, const output::Atlas& atlas, uint32_t p,
                   const std::string& out) {
    const auto& page = atlas.pages[p];
    const size_t texels = size_t(page.width) * page.height;
    std::vector<float> rgba(texels * 4);
    output::ComputePage(view, atlas, p, output::MapContent::Radiosity,
                        [&](std::span<const float> px, uint32_t first, uint32_t) {
                            std::copy(px.begin(), px.end(),
                                      rgba.begin() + ptrdiff_t(first) * page.width * 4);
                        });
    MarkLeafLevels(view, atlas, p, rgba);
    WriteHalfMap(fmt::format("{}/lightmap.{}.half", out, p), rgba);
    std::vector<float> e(texels * 9);
    output::ComputePage(view, atlas, p, output::MapContent::Irradiance,
                        [&](std::span<const float> px, uint32_t first, uint32_t) {
                            std::copy(px.begin(), px.end(),
                                      e.begin() + ptrdiff_t(first) * page.width * 9);
                        });
    const char* axis = "xyz";
    for (int a = 0; a < 3; ++a) {
        // Channels E.x.R E.x.G E.x.B E.y.R ...: axis a of colour c at 3 a + c.
        for (size_t t = 0; t < texels; ++t) {
            for (int c = 0; c < 3; ++c)
                rgba[4 * t + size_t(c)] = e[9 * t + size_t(3 * a + c)];
            rgba[4 * t + 3] = 1;
        }
        WriteHalfMap(fmt::format("{}/E.{}.{}.half", out, axis[a], p), rgba);
    }
}

json MaterialExtras(const solve::Material& m, uint32_t page) {
    return {{"page", page},
            {"albedo", Vec(m.albedo)},
            {"emission", Vec(m.emission)},
            {"use_vertex_colors", m.use_vertex_colors},
            {"color_factor", m.color_factor},
            {"glossy_exponent", m.glossy_exponent},
            {"glossy_weight", m.glossy_weight}};
}

// Mesh chunks: whole charts until a chunk holds chunk_triangles; one primitive per (atlas
// page, material) and one line primitive of chart outlines per chunk.
class ChunkWriter {
public:
    ChunkWriter(const output::BakeView& view, const output::Atlas& atlas, std::string out,
                const WebDataOptions& o)
        : view_(view), atlas_(atlas), out_(std::move(out)), opt_(o) {}

    void Add(uint32_t chart, const stream::ChartTile& tile) {
        const uint32_t page = atlas_.charts[chart].page;
        std::vector<uint32_t> local(tile.position.size());
        std::map<uint32_t, std::vector<uint32_t>> by_material;  // packed id -> triangles
        for (uint32_t t = 0; t < tile.triangles.size(); ++t)
            by_material[tile.material[t]].push_back(t);
        for (const auto& [packed, tris] : by_material) {
            GlbPrimitive& p = prims_[{page, packed}];
            std::fill(local.begin(), local.end(), UINT32_MAX);
            for (uint32_t t : tris)
                for (uint32_t v : tile.triangles[t]) {
                    if (local[v] == UINT32_MAX) {
                        local[v] = uint32_t(p.position.size());
                        AddVertex(p, chart, tile, v);
                    }
                    p.indices.push_back(local[v]);
                }
            triangles_ += tris.size();
        }
        AddOutline(chart, tile);
        if (triangles_ >= opt_.chunk_triangles)
            Flush();
    }

    void Flush() {
        if (prims_.empty())
            return;
        WebGlb glb(opt_.meshopt);
        for (auto& [key, p] : prims_) {
            p.material =
                glb.AddMaterial(fmt::format("page{}.material{}", key.first, key.second),
                                MaterialExtras(view_.scene.MaterialOf(key.second), key.first));
            stats_.vertices += p.position.size();
            glb.AddPrimitive(std::move(p));
        }
        outline_.material = glb.AddMaterial("chart borders", {{"borders", true}});
        outline_.lines = true;
        glb.AddPrimitive(std::move(outline_));
        const auto bytes = glb.Finish();
        const std::string name = fmt::format("mesh.{:03}.glb", stats_.chunks);
        WriteFile(out_ + "/" + name, bytes);
        names_.push_back(name);
        stats_.triangles += triangles_;
        stats_.mesh_bytes += bytes.size();
        ++stats_.chunks;
        prims_.clear();
        outline_ = {};
        triangles_ = 0;
    }

    const std::vector<std::string>& names() const { return names_; }
    const WebDataStats& stats() const { return stats_; }

private:
    void AddVertex(GlbPrimitive& p, uint32_t chart, const stream::ChartTile& tile, uint32_t v) {
        p.position.push_back(tile.position[v]);
        p.normal.push_back(tile.normal[v]);
        p.chart_uv.push_back(tile.uv[v]);
        p.atlas_uv.push_back(atlas_.AtlasUv(chart, tile.uv[v]));
        const Vec3f c = tile.color.empty() ? Vec3f(-1, -1, -1) : tile.color[v];
        if (c.x >= 0 && p.color.empty())
            p.color.assign(p.position.size() - 1, {0, 0, 0, 0});
        if (c.x >= 0)
            p.color.push_back({c.x, c.y, c.z, 1});
        else if (!p.color.empty())
            p.color.push_back({0, 0, 0, 0});
    }

    // Edges of one triangle only: the chart's outline (holes included).
    void AddOutline(uint32_t chart, const stream::ChartTile& tile) {
        std::map<std::pair<uint32_t, uint32_t>, int> edges;
        for (const auto& t : tile.triangles)
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = t[k], b = t[(k + 1) % 3];
                ++edges[{std::min(a, b), std::max(a, b)}];
            }
        for (const auto& [e, n] : edges) {
            if (n != 1)
                continue;
            for (uint32_t v : {e.first, e.second}) {
                outline_.indices.push_back(uint32_t(outline_.position.size()));
                outline_.position.push_back(tile.position[v]);
                outline_.normal.push_back(tile.normal[v]);
                outline_.chart_uv.push_back(tile.uv[v]);
                outline_.atlas_uv.push_back(atlas_.AtlasUv(chart, tile.uv[v]));
            }
        }
    }

    const output::BakeView& view_;
    const output::Atlas& atlas_;
    std::string out_;
    WebDataOptions opt_;
    std::map<std::pair<uint32_t, uint32_t>, GlbPrimitive> prims_;
    GlbPrimitive outline_;
    uint64_t triangles_ = 0;
    std::vector<std::string> names_;
    WebDataStats stats_;
};

json SkyJson(const solve::Sky& sky) {
    const char* type = sky.type == solve::Sky::Type::Uniform    ? "uniform"
                       : sky.type == solve::Sky::Type::Overcast ? "overcast"
                                                                : "none";
    return {{"type", type}, {"radiance", Vec(sky.radiance)}, {"up", Vec(sky.up)}};
}

}  // namespace

std::string ResolveBakeDirectory(const std::string& dir) {
    if (const std::string found = stream::BakeDirectoryIn(dir); stream::IsBakeDirectory(found))
        return found;
    if (!fs::exists(dir))  // a missing input, as for the other commands (exit 1)
        IoError({dir}, "no such directory");
    UsageError("{}: not a bake directory (no manifest.json, nor scene.mebake/manifest.json); "
               "make one with `mebake bake` or `mebake ingest`",
               dir);
}

bool WebDataCurrent(const std::string& bake_dir, const std::string& out) {
    std::error_code ec;
    const auto made = fs::last_write_time(out + "/view.json", ec);
    if (ec)
        return false;
    const auto solved = fs::last_write_time(solve::SolutionPath(bake_dir), ec);
    return !ec && made >= solved;
}

WebDataStats WriteWebData(const std::string& bake_dir, const std::string& out,
                          const WebDataOptions& o) {
    const output::BakeView view = output::OpenBakeView(bake_dir, output::FieldLoading::OnDemand);
    output::AtlasOptions ao;
    ao.max_size = o.max_atlas;
    ao.gutter = o.gutter;
    const output::Atlas atlas = output::PackAtlas(output::ChartResolutions(view), ao);
    fs::create_directories(out);
    fs::remove(out + "/view.json");  // written last: its presence means complete
    for (uint32_t p = 0; p < atlas.pages.size(); ++p)
        WritePageMaps(view, atlas, p, out);

    ChunkWriter chunks(view, atlas, out, o);
    const auto all = output::AllCharts(view);
    output::ForEachTile(
        view, all, stream::TileParts::Mesh, [](uint32_t, stream::ChartTile&) { return 0; },
        [&](uint32_t c, const stream::ChartTile& tile, int) { chunks.Add(c, tile); });
    chunks.Flush();

    json pages = json::array();
    for (const auto& p : atlas.pages)
        pages.push_back({{"width", p.width}, {"height", p.height}});
    const output::Camera cam = output::DefaultCamera(view, 800, 600);
    json j = {{"format", 1},
              {"unknown", view.solution.radiosity ? "radiosity" : "irradiance"},
              {"pages", pages},
              {"chunks", chunks.names()},
              {"triangles", chunks.stats().triangles},
              {"charts", view.chart_count()},
              {"meshopt", o.meshopt},
              {"bbox", {Vec(view.manifest.bbox_min), Vec(view.manifest.bbox_max)}},
              {"sky", SkyJson(view.scene.sky)},
              {"camera",
               {{"eye", Vec(cam.eye)},
                {"target", Vec(cam.target)},
                {"up", Vec(cam.up)},
                {"fov", cam.fov}}}};
    const std::string text = j.dump(1) + "\n";
    WriteFile(out + "/view.json", {reinterpret_cast<const uint8_t*>(text.data()), text.size()});
    WebDataStats st = chunks.stats();
    st.pages = uint32_t(atlas.pages.size());
    return st;
}

}  // namespace mebake::view
