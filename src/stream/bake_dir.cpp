#include "stream/bake_dir.h"

#include "core/checksum.h"
#include "core/error.h"
#include "io/byte_stream.h"
#include "io/chunk_file.h"

#include <cerrno>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <unistd.h>
#include <vector>

namespace mebake::stream {

using nlohmann::json;

std::string ManifestPath(const std::string& dir) {
    return dir + "/manifest.json";
}
std::string ProxyPath(const std::string& dir) {
    return dir + "/proxy.bin";
}
std::string TilePath(const std::string& dir, uint32_t chart) {
    char name[32];
    std::snprintf(name, sizeof(name), "/tiles/c%06u.tile", chart);
    return dir + name;
}

bool IsBakeDirectory(const std::string& path) {
    return std::filesystem::is_directory(path) && std::filesystem::exists(ManifestPath(path));
}

std::string BakeDirectoryIn(const std::string& path) {
    const std::string inner = (std::filesystem::path(path) / "scene.mebake").string();
    return !IsBakeDirectory(path) && IsBakeDirectory(inner) ? inner : path;
}

namespace {
json Vec(const Vec3d& v) {
    return {v.x, v.y, v.z};
}
json Vec(const Vec3f& v) {
    return {v.x, v.y, v.z};
}
Vec3d ToVec3d(const json& j) {
    return {j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()};
}
}  // namespace

void WriteManifest(const std::string& dir, const Manifest& m) {
    json j;
    j["format"] = "mebake";
    j["version"] = m.version;
    j["state"] = m.state;
    j["inputs"] = json::array();
    for (const auto& in : m.inputs)
        j["inputs"].push_back({{"path", in.path},
                               {"bytes", in.bytes},
                               {"vertices", in.vertices},
                               {"triangles", in.triangles},
                               {"first_vertex", in.first_vertex},
                               {"first_face", in.first_face},
                               {"has_colors", in.has_colors},
                               {"materials", in.materials},
                               {"mtllibs", in.mtllibs}});
    for (size_t k = 0; k < m.inputs.size(); ++k)
        if (m.inputs[k].hashed)
            j["inputs"][k]["identity"] = {{"size", m.inputs[k].file_size},
                                          {"crc32", m.inputs[k].crc32}};
    j["settings"] = {{"texel_size", m.texel_size},
                     {"brick_faces", m.brick_faces},
                     {"max_distortion", m.max_distortion},
                     {"memory_budget", m.memory_budget}};
    if (!m.options.empty()) {
        j["options"] = json::object();
        for (const auto& [k, v] : m.options)
            j["options"][k] = v;
    }
    j["vertex_count"] = m.vertex_count;
    j["face_count"] = m.face_count;
    j["bbox"] = {Vec(m.bbox_min), Vec(m.bbox_max)};
    if (m.ground) {
        j["ground"] = true;
        j["object_bbox"] = {Vec(m.object_bbox_min), Vec(m.object_bbox_max)};
    }
    j["up"] = Vec(m.up);
    j["surface_area"] = m.surface_area;
    j["brick_count"] = m.brick_count;
    j["orientation"] = {{"components", m.orientation.components},
                        {"flipped", m.orientation.flipped},
                        {"flipped_triangles", m.orientation.flipped_triangles},
                        {"nested_kept", m.orientation.nested_kept}};
    j["charts"] = json::array();
    for (const auto& c : m.charts)
        j["charts"].push_back({{"brick", c.brick},
                               {"triangles", c.triangles},
                               {"vertices", c.vertices},
                               {"resolution", c.resolution},
                               {"scale", c.scale},
                               {"area", c.area},
                               {"area_distortion", c.area_distortion},
                               {"virtual_fraction", c.virtual_fraction},
                               {"bbox", {Vec(c.bbox_min), Vec(c.bbox_max)}}});
    j["proxy"] = {{"triangles", m.proxy_triangles},
                  {"deviation", m.proxy_deviation},
                  {"cell_size", m.proxy_cell_size}};
    j["timings"] = json::object();
    for (const auto& [k, v] : m.timings)
        j["timings"][k] = v;
    auto out = io::OutputStream::Open(ManifestPath(dir));
    out->Write(j.dump(1));
    out->Write("\n");
    out->Commit();
    io::SyncDirectory(dir);
}

Manifest ReadManifest(const std::string& dir) {
    std::string path = ManifestPath(dir);
    std::ifstream f(path);
    if (!f)
        IoError({path}, "cannot open (is {} a bake directory made by `mebake ingest`?)", dir);
    Manifest m;
    try {
        json j = json::parse(f);
        if (j.at("format") != "mebake")
            CorruptError({path}, "not a mebake manifest");
        m.version = j.at("version").get<int>();
        if (m.version != kManifestVersion)
            CorruptError({path}, "manifest version {} is not supported (expected {})", m.version,
                         kManifestVersion);
        m.state = j.at("state").get<std::string>();
        for (const auto& in : j.at("inputs")) {
            InputRecord r;
            r.path = in.at("path");
            r.bytes = in.at("bytes");
            r.vertices = in.at("vertices");
            r.triangles = in.at("triangles");
            r.first_vertex = in.at("first_vertex");
            r.first_face = in.at("first_face");
            r.has_colors = in.at("has_colors");
            r.materials = in.at("materials").get<std::vector<std::string>>();
            r.mtllibs = in.at("mtllibs").get<std::vector<std::string>>();
            if (in.contains("identity")) {
                r.hashed = true;
                r.file_size = in.at("identity").at("size");
                r.crc32 = in.at("identity").at("crc32");
            }
            m.inputs.push_back(r);
        }
        const auto& s = j.at("settings");
        m.texel_size = s.at("texel_size");
        m.brick_faces = s.at("brick_faces");
        m.max_distortion = s.at("max_distortion");
        m.memory_budget = s.at("memory_budget");
        if (j.contains("options"))
            for (const auto& [k, v] : j.at("options").items())
                m.options.emplace_back(k, v.get<std::string>());
        m.vertex_count = j.at("vertex_count");
        m.face_count = j.at("face_count");
        m.bbox_min = ToVec3d(j.at("bbox").at(0));
        m.bbox_max = ToVec3d(j.at("bbox").at(1));
        m.ground = j.value("ground", false);
        m.object_bbox_min = m.ground ? ToVec3d(j.at("object_bbox").at(0)) : m.bbox_min;
        m.object_bbox_max = m.ground ? ToVec3d(j.at("object_bbox").at(1)) : m.bbox_max;
        if (j.contains("up"))
            m.up = ToVec3d(j.at("up"));
        m.surface_area = j.at("surface_area");
        m.brick_count = j.at("brick_count");
        if (j.contains("orientation")) {
            const auto& o = j.at("orientation");
            m.orientation.components = o.at("components");
            m.orientation.flipped = o.at("flipped");
            m.orientation.flipped_triangles = o.at("flipped_triangles");
            m.orientation.nested_kept = o.at("nested_kept");
        }
        for (const auto& c : j.at("charts")) {
            ChartRecord r;
            r.brick = c.at("brick");
            r.triangles = c.at("triangles");
            r.vertices = c.at("vertices");
            r.resolution = c.at("resolution");
            r.scale = c.at("scale");
            r.area = c.at("area");
            r.area_distortion = c.at("area_distortion");
            r.virtual_fraction = c.at("virtual_fraction");
            r.bbox_min = Vec3f(ToVec3d(c.at("bbox").at(0)));
            r.bbox_max = Vec3f(ToVec3d(c.at("bbox").at(1)));
            m.charts.push_back(r);
        }
        m.proxy_triangles = j.at("proxy").at("triangles");
        m.proxy_deviation = j.at("proxy").at("deviation");
        m.proxy_cell_size = j.at("proxy").value("cell_size", 0.0);
        for (const auto& [k, v] : j.at("timings").items())
            m.timings.emplace_back(k, v.get<double>());
    } catch (const json::exception& e) {
        CorruptError({path}, "malformed manifest: {}", e.what());
    }
    return m;
}

void HashFile(const std::string& path, uint64_t* size, uint32_t* crc32) {
    const bool is_stdin = path == "-";
    int fd = is_stdin ? 0 : ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        IoError({path}, "cannot open: {}", ErrnoString(errno));
    if (!is_stdin)
        ::posix_fadvise(fd, 0, 0, POSIX_FADV_SEQUENTIAL);
    std::vector<uint8_t> buf(size_t(4) << 20);
    uint64_t total = 0;
    uint32_t crc = 0;
    for (;;) {
        ssize_t n = ::read(fd, buf.data(), buf.size());
        if (n < 0) {
            if (errno == EINTR)
                continue;
            int err = errno;
            if (!is_stdin)
                ::close(fd);
            IoError({is_stdin ? "<stdin>" : path, total}, "read failed: {}", ErrnoString(err));
        }
        if (n == 0)
            break;
        crc = Crc32(buf.data(), size_t(n), crc);
        total += uint64_t(n);
    }
    if (!is_stdin)
        ::close(fd);
    *size = total;
    *crc32 = crc;
}

}  // namespace mebake::stream
