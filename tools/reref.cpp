// reref: re-addresses the points of a `mebake reference` JSON to another ingest of the same
// input, so that two bakes whose charts differ are scored at the same points (`mebake
// compare` reads a point's chart, triangle and barycentrics). A point is found again by its
// input face id (the tiles' FGID) and its barycentrics are reordered to the new triangle's
// corners (matched by input vertex id). Points on hole-fill triangles (no face id) or on
// faces the other ingest does not have are dropped and counted. So are points whose shading
// normal (the tile's vertex normals interpolated, as `mebake reference` computes it) is not
// the one the reference recorded: the reference's B is the integral over that normal's
// hemisphere (docs/accuracy.md), and a chart border that moves onto a crease changes the
// vertex normals there (stream/chart_builder.cpp, kCreaseCos). Nefertiti's merged ingest
// (session 15) had one such point, 12 -> 36 degrees from its face, that made 73 % of the
// bake's squared error at the paired points.
//
//   reref REF.json DIR -o OUT.json
#include "core/error.h"
#include "core/vec.h"
#include "stream/bake_dir.h"
#include "stream/tile.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <fstream>
#include <unordered_map>

using namespace mebake;

namespace {

struct Site {
    uint32_t chart, triangle;
    std::array<uint64_t, 3> vertex;  // input vertex ids of the triangle's corners
    std::array<Vec3f, 3> position, normal;  // the corners' positions and shading normals
};

// More than this between the recorded and the new shading normal: another normal (float
// rounding of the same one is far below).
constexpr double kSameNormalCos = 0.9999985;  // cos 0.1 degree

// The shading normal at barycentrics b of a site, as reference.cpp's SurfaceAt computes it.
Vec3d ShadingNormal(const Site& s, const std::array<double, 3>& b) {
    const Vec3d p0(s.position[0]), p1(s.position[1]), p2(s.position[2]);
    const Vec3d face = Normalize(Cross(p1 - p0, p2 - p0));
    Vec3d n{};
    for (int k = 0; k < 3; ++k)
        n += Vec3d(s.normal[size_t(k)]) * b[size_t(k)];
    n = Normalize(n);
    return Dot(n, face) > 0 ? n : face;
}

std::unordered_map<uint64_t, Site> SitesByFace(const std::string& dir) {
    const stream::Manifest m = stream::ReadManifest(dir);
    std::unordered_map<uint64_t, Site> sites;
    for (uint32_t c = 0; c < m.charts.size(); ++c) {
        const stream::ChartTile t = stream::ReadTile(stream::TilePath(dir, c), stream::TileParts::Mesh);
        for (uint32_t k = 0; k < t.triangles.size(); ++k) {
            const auto& tri = t.triangles[k];
            sites[t.face_id[k]] = {c,
                                   k,
                                   {t.vertex_id[tri[0]], t.vertex_id[tri[1]], t.vertex_id[tri[2]]},
                                   {t.position[tri[0]], t.position[tri[1]], t.position[tri[2]]},
                                   {t.normal[tri[0]], t.normal[tri[1]], t.normal[tri[2]]}};
        }
    }
    return sites;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Re-address a mebake reference's points to another ingest of the same input"};
    std::string ref_path, dir, out_path;
    app.add_option("reference", ref_path, "JSON from `mebake reference`")->required();
    app.add_option("dir", dir, "Bake directory of the other ingest")->required();
    app.add_option("-o,--output", out_path, "Re-addressed reference (JSON)")->required();
    CLI11_PARSE(app, argc, argv);
    try {
        std::ifstream in(ref_path);
        if (!in) IoError({ref_path}, "cannot open");
        nlohmann::json ref = nlohmann::json::parse(in);
        const auto sites = SitesByFace(dir);
        nlohmann::json kept = nlohmann::json::array();
        size_t dropped = 0, other_normal = 0;
        for (auto& p : ref.at("points")) {
            const auto it = p["face"].is_number() ? sites.find(p["face"].get<uint64_t>()) : sites.end();
            if (it == sites.end()) {
                ++dropped;
                continue;
            }
            const Site& s = it->second;
            std::array<double, 3> bary{};
            bool found = true;
            for (int k = 0; k < 3 && found; ++k) {
                found = false;
                for (int j = 0; j < 3; ++j)
                    if (p["vertex_ids"][j].get<uint64_t>() == s.vertex[k]) {
                        bary[k] = p["barycentric"][j].get<double>();
                        found = true;
                    }
            }
            if (!found) {
                ++dropped;
                continue;
            }
            if (p.contains("normal")) {
                const Vec3d recorded(p["normal"][0].get<double>(), p["normal"][1].get<double>(),
                                     p["normal"][2].get<double>());
                if (Dot(Normalize(recorded), ShadingNormal(s, bary)) < kSameNormalCos) {
                    ++other_normal;
                    continue;
                }
            }
            p["chart"] = s.chart;
            p["triangle"] = s.triangle;
            p["barycentric"] = bary;
            p["vertex_ids"] = s.vertex;
            kept.push_back(std::move(p));
        }
        std::fprintf(stderr,
                     "%zu points re-addressed, %zu dropped, %zu dropped for another shading "
                     "normal\n",
                     kept.size(), dropped, other_normal);
        ref["points"] = std::move(kept);
        ref["dir"] = dir;
        std::ofstream out(out_path);
        out << ref.dump(1) << "\n";
        if (!out) IoError({out_path}, "cannot write");
    } catch (const nlohmann::json::exception& e) {
        std::fprintf(stderr, "reref: %s: %s\n", ref_path.c_str(), e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "reref: %s\n", e.what());
        return 1;
    }
    return 0;
}
