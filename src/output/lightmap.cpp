#include "output/lightmap.h"

#include "core/check.h"
#include "core/error.h"
#include "core/log.h"
#include "core/memory_budget.h"
#include "core/parallel.h"
#include "io/png_writer.h"
#include "output/texel_stitch.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <memory>
#include <numbers>

namespace mebake::output {

namespace {

// Radiance = B / pi, divided as shading.cpp does so the glossy path agrees to the bit.
constexpr float kPi = float(std::numbers::pi);

// The tiles, shaders and stitched texels of a group of charts.
struct ChartGroup {
    std::vector<stream::ChartTile> tiles;
    std::vector<std::shared_ptr<const ChartField>> fields;
    std::vector<std::unique_ptr<ChartShader>> shaders;
    std::vector<StitchedTexels> stitched;  // empty without a stitch
};

ChartGroup LoadCharts(const BakeView& view, const Atlas& atlas, std::span<const uint32_t> charts,
                      const TexelStitch* stitch) {
    ChartGroup g;
    const size_t n = charts.size();
    g.tiles.resize(n);
    g.fields.resize(n);
    g.shaders.resize(n);
    if (stitch)
        g.stitched.resize(n);
    ParallelFor(0, int64_t(n), [&](int64_t k) {
        const uint32_t c = charts[size_t(k)];
        if (stitch)
            g.stitched[size_t(k)] = stitch->Chart(c);
        const std::string path = view.TilePath(c);
        auto& tile = g.tiles[size_t(k)];
        tile = stream::ReadTile(path, stream::TileParts::Mesh);
        if (tile.meta.resolution != atlas.charts[c].resolution)
            CorruptError({path}, "resolution {} but the manifest says {}", tile.meta.resolution,
                         atlas.charts[c].resolution);
        g.fields[size_t(k)] = view.Field(c);
        g.shaders[size_t(k)] = std::make_unique<ChartShader>(
            tile, *g.fields[size_t(k)], view.solution.radiosity, view.scene, path,
            view.Seams(c));
    });
    return g;
}

}  // namespace

int MapChannels(MapContent content) {
    return content == MapContent::Radiosity ? 4 : 9;
}

std::vector<std::string> MapChannelNames(MapContent content) {
    if (content == MapContent::Radiosity)
        return {"R", "G", "B", "A"};
    std::vector<std::string> names;
    for (const char* axis : {"x", "y", "z"})
        for (const char* colour : {"R", "G", "B"})
            names.push_back(std::string("E.") + axis + "." + colour);
    return names;
}

void ShadeTexel(const ChartShader& shader, Vec2f uv, MapContent content, float* px) {
    if (content == MapContent::Radiosity) {
        const Vec3f b = shader.Radiosity(shader.AtUv(uv));
        px[0] = b.x;
        px[1] = b.y;
        px[2] = b.z;
        px[3] = 1;
        return;
    }
    Vec3f e[3];
    shader.Irradiance(uv, e);
    for (int axis = 0; axis < 3; ++axis)
        for (int c = 0; c < 3; ++c)
            px[axis * 3 + c] = e[c][axis];
}

void FillChartBlock(const ChartShader& shader, const Atlas& atlas, uint32_t chart,
                    MapContent content, uint32_t row_begin, uint32_t row_end, float* out,
                    size_t stride, const StitchedTexels* stitch) {
    const uint32_t g = atlas.gutter, res = atlas.charts[chart].resolution, block = res + 2 * g;
    CHECK_LE(row_end, block);
    const size_t nc = size_t(MapChannels(content));
    for (uint32_t by = row_begin; by < row_end; ++by) {
        float* row = out + size_t(by - row_begin) * stride;
        // The square's texels, then the left and right gutters as copies of its border.
        const uint32_t j = std::clamp(by, g, g + res - 1) - g;
        for (uint32_t bx = g; bx < g + res; ++bx) {
            float* px = row + size_t(bx) * nc;
            if (const float* s = stitch ? stitch->Find(j * res + bx - g, int(nc)) : nullptr)
                std::copy_n(s, nc, px);
            else
                ShadeTexel(shader, atlas.TexelUv(chart, bx, by), content, px);
        }
        for (uint32_t bx = 0; bx < g; ++bx) {
            std::copy_n(row + size_t(g) * nc, nc, row + size_t(bx) * nc);
            std::copy_n(row + size_t(g + res - 1) * nc, nc, row + size_t(g + res + bx) * nc);
        }
    }
}

void ComputePage(const BakeView& view, const Atlas& atlas, uint32_t page, MapContent content,
                 const PageSink& sink, uint32_t band_rows, size_t group,
                 const TexelStitch* stitch) {
    CHECK_LT(page, atlas.pages.size());
    CHECK_GE(band_rows, 1u);
    const AtlasPage& pg = atlas.pages[page];
    const size_t nc = size_t(MapChannels(content)), stride = size_t(pg.width) * nc;
    // A shelf's rows are computed into one buffer, a group of charts at a time, then
    // handed out in bands: memory holds one shelf's rows and one group's tiles, however
    // many charts a shelf has (an 8192-wide page holds 62 charts of 128 texels per shelf).
    if (group == 0)
        group = size_t(std::max(1, 2 * MaxThreads()));
    std::vector<float> rows_buffer;
    uint32_t y = 0;
    auto emit = [&](uint32_t first, uint32_t count) {  // rows of rows_buffer
        for (uint32_t r = 0; r < count;) {
            const uint32_t n = std::min(band_rows, count - r);
            sink(
                std::span<const float>(rows_buffer.data() + size_t(r) * stride, size_t(n) * stride),
                first + r, n);
            r += n;
        }
        y = first + count;
    };
    auto emit_empty = [&](uint32_t until) {
        if (y >= until)
            return;
        rows_buffer.assign(size_t(std::min(band_rows, until - y)) * stride, 0.f);
        while (y < until) {
            const uint32_t rows = std::min(band_rows, until - y);
            sink(std::span<const float>(rows_buffer.data(), size_t(rows) * stride), y, rows);
            y += rows;
        }
    };
    for (const AtlasShelf& shelf : pg.shelves) {
        emit_empty(shelf.y);
        CHECK_EQ(y, shelf.y);
        rows_buffer.assign(size_t(shelf.height) * stride, 0.f);
        const std::span<const uint32_t> all(shelf.charts);
        for (size_t first = 0; first < all.size(); first += group) {
            // The last group's tiles, fields and shaders leave holes in the two threads'
            // heaps that stay resident and add up over thousands of charts (40+ MB at 100M
            // triangles): back to the system before the next group.
            if (first > 0)
                ReturnFreedHeap();
            const auto charts = all.subspan(first, std::min(group, all.size() - first));
            const ChartGroup g = LoadCharts(view, atlas, charts, stitch);
            // One task per (chart, row): each writes its own texels only.
            const uint32_t rows = shelf.height;
            ParallelFor(0, int64_t(charts.size()) * rows, [&](int64_t task) {
                const size_t k = size_t(task) / rows;
                const uint32_t r = uint32_t(size_t(task) % rows);
                const uint32_t c = charts[k];
                const AtlasChart& ac = atlas.charts[c];
                const uint32_t by = shelf.y + r - ac.y;
                if (by >= atlas.block(c))
                    return;  // a smaller block than the shelf's height
                float* out = rows_buffer.data() + size_t(r) * stride + size_t(ac.x) * nc;
                FillChartBlock(*g.shaders[k], atlas, c, content, by, by + 1, out, stride,
                               stitch ? &g.stitched[k] : nullptr);
            });
        }
        emit(shelf.y, shelf.height);
    }
    emit_empty(pg.height);
}

std::string Extension(const std::string& path) {
    std::string e = std::filesystem::path(path).extension().string();
    for (char& c : e)
        c = char(std::tolower(static_cast<unsigned char>(c)));
    return e;
}

std::string PagePath(const std::string& path, uint32_t page, uint32_t pages) {
    if (pages <= 1)
        return path;
    std::filesystem::path p(path);
    const std::string ext = p.extension().string();
    p.replace_extension();
    return p.string() + "." + std::to_string(1001 + page) + ext;
}

namespace {

// Radiance B/pi of a Radiosity band, tone-mapped to 8-bit sRGB RGB.
void ToneMapBand(std::span<const float> pixels, const ToneMap& tone, std::vector<uint8_t>& out) {
    const size_t texels = pixels.size() / 4;
    out.resize(texels * 3);
    ParallelForRange(
        0, int64_t(texels),
        [&](int64_t lo, int64_t hi) {
            for (int64_t t = lo; t < hi; ++t) {
                const float* p = &pixels[size_t(t) * 4];
                ToneMapPixel(Vec3f(p[0], p[1], p[2]) / kPi, tone, &out[size_t(t) * 3]);
            }
        },
        4096);
}

void WritePngPage(const BakeView& view, const Atlas& atlas, uint32_t page, const ToneMap& tone,
                  const TexelStitch* stitch, io::OutputStream& out) {
    const AtlasPage& pg = atlas.pages[page];
    io::PngWriter png(out, int(pg.width), int(pg.height), 3);
    std::vector<uint8_t> bytes;
    ComputePage(view, atlas, page, MapContent::Radiosity,
                [&](std::span<const float> pixels, uint32_t, uint32_t rows) {
                    ToneMapBand(pixels, tone, bytes);
                    png.WriteRows(bytes, int(rows));
                },
                64, 0, stitch);
    png.Finish();
}

}  // namespace

std::vector<std::string> WriteMapPages(const BakeView& view, const Atlas& atlas,
                                       const std::string& path, MapContent content,
                                       const MapWriteOptions& options) {
    const std::string ext = path == "-" ? ".exr" : Extension(path);
    const bool png = ext == ".png";
    if (!png && ext != ".exr")
        UsageError("{}: expected a .exr{} file name", path,
                   content == MapContent::Radiosity ? " or .png" : "");
    if (png && content != MapContent::Radiosity)
        UsageError("{}: vector irradiance maps are written as OpenEXR (.exr) only", path);
    const bool png_too = !options.png_path.empty();
    if (png_too && (png || content != MapContent::Radiosity || Extension(options.png_path) != ".png"))
        UsageError("{}: a PNG companion needs a radiosity .exr map and a .png name",
                   options.png_path);
    const uint32_t pages = uint32_t(atlas.pages.size());
    if (path == "-" && pages > 1)
        UsageError("the atlas has {} pages; give a file name instead of '-'", pages);
    const auto stitch = StitchForView(view, atlas, content, options.stitch_memory);
    std::vector<std::string> written;
    for (uint32_t p = 0; p < pages; ++p) {
        const std::string file = PagePath(path, p, pages);
        const AtlasPage& pg = atlas.pages[p];
        if (png) {
            auto out = io::OutputStream::Open(file);
            WritePngPage(view, atlas, p, options.tone, stitch.get(), *out);
            out->Commit();
        } else {
            io::ExrOptions eo;
            eo.type = options.exr_type;
            eo.compression = options.compression;
            eo.comments = content == MapContent::Radiosity
                              ? "mebake light map: radiosity B (W/m^2, linear) in R G B; A = 1 on "
                                "chart texels"
                              : "mebake vector irradiance E (W/m^2, world axes): layers E.x E.y "
                                "E.z, channels R G B";
            eo.attributes = {
                {"mebakeContent", content == MapContent::Radiosity ? "radiosity" : "irradiance"},
                {"mebakePage", fmt::format("{} of {}", p + 1, pages)},
                {"mebakeGutter", std::to_string(atlas.gutter)}};
            io::ExrWriter w(file, int(pg.width), int(pg.height), MapChannelNames(content), eo);
            std::unique_ptr<io::OutputStream> png_out;
            std::unique_ptr<io::PngWriter> png_w;
            if (png_too) {
                png_out = io::OutputStream::Open(PagePath(options.png_path, p, pages));
                png_w = std::make_unique<io::PngWriter>(*png_out, int(pg.width), int(pg.height), 3);
            }
            std::vector<uint8_t> bytes;
            ComputePage(view, atlas, p, content,
                        [&](std::span<const float> pixels, uint32_t, uint32_t rows) {
                            // Two encoders of the same rows, each single-threaded (ZIP,
                            // deflate): side by side, each streaming its rows in order.
                            TaskGroup encoders;
                            if (png_w)
                                encoders.Run([&] {  // the bytes WritePngPage writes
                                    ToneMapBand(pixels, options.tone, bytes);
                                    png_w->WriteRows(bytes, int(rows));
                                });
                            encoders.Run([&] { w.WriteRows(pixels, int(rows)); });
                            encoders.Wait();
                        },
                        64, 0, stitch.get());
            w.Commit();
            if (png_w) {
                png_w->Finish();
                png_out->Commit();
            }
        }
        written.push_back(file);
    }
    for (uint32_t p = 0; png_too && p < pages; ++p)
        written.push_back(PagePath(options.png_path, p, pages));
    return written;
}

std::vector<uint8_t> EncodeLightMapPng(const BakeView& view, const Atlas& atlas, uint32_t page,
                                       const ToneMap& tone, const TexelStitch* stitch) {
    std::vector<uint8_t> bytes;
    auto out = io::OutputStream::ToMemory(&bytes);
    WritePngPage(view, atlas, page, tone, stitch, *out);
    out->Commit();
    return bytes;
}

std::unique_ptr<TexelStitch> StitchForView(const BakeView& view, const Atlas& atlas,
                                           MapContent content, uint64_t memory_bytes) {
    if (!view.stitched())
        return nullptr;
    TexelStitchStats s;
    auto stitch = std::make_unique<TexelStitch>(StitchTexels(view, atlas, content, &s, memory_bytes));
    spdlog::info("{} seams: {} texels, {} samples, bilinear mismatch rms {:.4g} -> {:.4g} ({} "
                 "iterations)",
                 content == MapContent::Radiosity ? "light map" : "E map", s.texels, s.samples,
                 s.rms_before, s.rms_after, s.iterations);
    spdlog::debug("texel stitch: samples {}, channels {}", s.rows_in_memory ? "in memory" : "on disk",
                  s.channels_in_parallel ? "in parallel" : "in turn");
    return stitch;
}

}  // namespace mebake::output
