// `mebake info <mesh>` and `mebake convert <in> <out>`: streaming passes over one mesh.
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "app/commands.h"
#include "core/error.h"
#include "core/log.h"
#include "core/units.h"
#include "io/byte_stream.h"
#include "io/mesh_format.h"
#include "io/mesh_stats.h"
#include "stream/bake_dir.h"

namespace mebake::app {

namespace {

nlohmann::json StatsToJson(const io::MeshStats& s) {
    nlohmann::json j;
    j["source"] = s.header.source;
    j["format"] = io::FormatName(s.header.format);
    j["encoding"] = s.header.encoding;
    j["vertices"] = s.summary.vertex_count;
    j["faces"] = s.summary.face_count;
    j["triangles"] = s.triangles;
    j["bbox_min"] = {s.bbox_min.x, s.bbox_min.y, s.bbox_min.z};
    j["bbox_max"] = {s.bbox_max.x, s.bbox_max.y, s.bbox_max.z};
    j["properties"] = {{"normals", s.header.has_normals},
                       {"colors", s.header.has_colors},
                       {"alpha", s.header.has_alpha},
                       {"uvs", s.header.has_uvs}};
    nlohmann::json hist = nlohmann::json::object();
    for (auto [corners, count] : s.face_sizes) hist[std::to_string(corners)] = count;
    j["face_sizes"] = hist;
    j["degenerate_faces"] = s.degenerate_faces;
    j["zero_area_faces"] = s.zero_area_faces;
    j["unreferenced_vertices"] = s.unreferenced_vertices;
    j["surface_area"] = s.surface_area;
    j["bytes_read"] = s.summary.bytes_read;
    j["read_seconds"] = s.read_seconds;
    j["comments"] = s.header.comments;
    j["obj_info"] = s.header.obj_info;
    j["skipped"] = s.header.skipped;
    j["materials"] = s.summary.materials;
    j["mtllibs"] = s.summary.mtllibs;
    j["groups"] = s.summary.groups;
    j["corner_uvs"] = s.summary.corner_uv_count;
    j["corner_normals"] = s.summary.corner_normal_count;
    return j;
}

void PrintStats(const io::MeshStats& s) {
    auto yes = [](bool b) { return b ? "yes" : "no"; };
    std::printf("source        %s (%s, %s)\n", s.header.source.c_str(),
                io::FormatName(s.header.format), s.header.encoding.c_str());
    std::printf("vertices      %llu\n", (unsigned long long)s.summary.vertex_count);
    std::printf("faces         %llu (%llu triangles)\n", (unsigned long long)s.summary.face_count,
                (unsigned long long)s.triangles);
    std::printf("bbox          (%g, %g, %g) - (%g, %g, %g)\n", s.bbox_min.x, s.bbox_min.y,
                s.bbox_min.z, s.bbox_max.x, s.bbox_max.y, s.bbox_max.z);
    std::printf("size          %g x %g x %g\n", s.bbox_max.x - s.bbox_min.x,
                s.bbox_max.y - s.bbox_min.y, s.bbox_max.z - s.bbox_min.z);
    std::printf("properties    normals %s, colors %s%s, uvs %s\n", yes(s.header.has_normals),
                yes(s.header.has_colors), s.header.has_alpha ? " (+alpha)" : "",
                yes(s.header.has_uvs));
    std::printf("face sizes   ");
    for (auto [corners, count] : s.face_sizes)
        std::printf(" %u:%llu", corners, (unsigned long long)count);
    std::printf("\n");
    std::printf("degenerate    %llu faces repeat a vertex, %llu have zero area\n",
                (unsigned long long)s.degenerate_faces, (unsigned long long)s.zero_area_faces);
    std::printf("unreferenced  %llu vertices\n", (unsigned long long)s.unreferenced_vertices);
    std::printf("surface area  %g\n", s.surface_area);
    if (!s.summary.materials.empty()) {
        std::printf("materials    ");
        for (auto& m : s.summary.materials) std::printf(" %s", m.c_str());
        std::printf("\n");
    }
    if (!s.summary.groups.empty())
        std::printf("groups        %zu\n", s.summary.groups.size());
    if (s.summary.corner_uv_count || s.summary.corner_normal_count)
        std::printf("corner attrs  %llu uvs, %llu normals (per corner, not per vertex)\n",
                    (unsigned long long)s.summary.corner_uv_count,
                    (unsigned long long)s.summary.corner_normal_count);
    for (auto& c : s.header.comments) std::printf("comment       %s\n", c.c_str());
    for (auto& c : s.header.obj_info) std::printf("obj_info      %s\n", c.c_str());
    if (!s.header.skipped.empty()) {
        std::printf("skipped      ");
        for (auto& k : s.header.skipped) std::printf(" %s", k.c_str());
        std::printf("\n");
    }
    double mb = double(s.summary.bytes_read) / (1 << 20);
    std::printf("read          %s in %s (%.0f MB/s, %s triangles/s)\n",
                FormatBytes(s.summary.bytes_read).c_str(), FormatSeconds(s.read_seconds).c_str(),
                s.read_seconds > 0 ? mb / s.read_seconds : 0.0,
                FormatCount(s.read_seconds > 0 ? double(s.triangles) / s.read_seconds : 0).c_str());
}

}  // namespace

int RunInfo(const InfoOptions& opt) {
    if (opt.input != "-" && std::filesystem::is_directory(opt.input))
        return RunBakeInfo(stream::BakeDirectoryIn(opt.input), opt.json);
    auto in = io::InputStream::Open(opt.input);
    io::MeshFormat format = io::DetectFormat(*in, opt.input, opt.format);
    io::MeshStatsSink sink;
    io::ReadMesh(*in, format, sink);
    const auto& s = sink.stats();
    if (opt.json) {
        std::printf("%s\n", StatsToJson(s).dump(2).c_str());
    } else {
        PrintStats(s);
    }
    return 0;
}

int RunConvert(const ConvertOptions& opt) {
    if (opt.output != "-" && !opt.force && std::filesystem::exists(opt.output))
        UsageError("{} exists; pass --force to overwrite it", opt.output);
    if (opt.ascii && opt.big_endian) UsageError("--ascii and --big-endian exclude each other");
    io::MeshFormat out_format = io::MeshFormat::Ply;
    if (opt.out_format) {
        out_format = *opt.out_format;
    } else if (auto f = io::FormatFromPath(opt.output)) {
        out_format = *f;
    } else if (opt.output != "-") {
        UsageError("cannot tell the output format of '{}'; use a .ply or .obj name or --to",
                   opt.output);
    }
    if (out_format != io::MeshFormat::Ply && out_format != io::MeshFormat::Obj)
        UsageError("mebake writes ply and obj, not {}", io::FormatName(out_format));

    io::WriteOptions wopt;
    wopt.ply_encoding = opt.ascii        ? io::PlyEncoding::Ascii
                        : opt.big_endian ? io::PlyEncoding::BinaryBigEndian
                                         : io::PlyEncoding::BinaryLittleEndian;
    wopt.normals = !opt.no_normals;
    wopt.colors = !opt.no_colors;
    wopt.uvs = !opt.no_uvs;
    wopt.float_colors = opt.float_colors;
    if (opt.output != "-") {
        auto parent = std::filesystem::path(opt.output).parent_path();
        wopt.temp_dir = parent.empty() ? "." : parent.string();
    }

    auto in = io::InputStream::Open(opt.input);
    io::MeshFormat in_format = io::DetectFormat(*in, opt.input, opt.in_format);
    auto out = io::OutputStream::Open(opt.output);
    auto writer = io::MakeMeshWriter(*out, out_format, wopt);
    auto t0 = std::chrono::steady_clock::now();
    io::ReadMesh(*in, in_format, *writer);
    double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    spdlog::info("converted {} ({}) -> {} ({}) in {}, {} read, {} written", in->name(),
                 io::FormatName(in_format), out->name(), io::FormatName(out_format),
                 FormatSeconds(secs), FormatBytes(in->offset()), FormatBytes(out->offset()));
    return 0;
}

}  // namespace mebake::app
