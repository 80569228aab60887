// reref: re-addresses the points of a `mebake reference` JSON to another ingest of the same
// input, so that two bakes whose charts differ are scored at the same points (`mebake
// compare` reads a point's chart, triangle and barycentrics). A point is found again by its
// input face id (the tiles' FGID) and its barycentrics are reordered to the new triangle's
// corners (matched by input vertex id). Points on hole-fill triangles (no face id) or on
// faces the other ingest does not have are dropped and counted.
//
//   reref REF.json DIR -o OUT.json
#include "core/error.h"
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
};

std::unordered_map<uint64_t, Site> SitesByFace(const std::string& dir) {
    const stream::Manifest m = stream::ReadManifest(dir);
    std::unordered_map<uint64_t, Site> sites;
    for (uint32_t c = 0; c < m.charts.size(); ++c) {
        const stream::ChartTile t = stream::ReadTile(stream::TilePath(dir, c), stream::TileParts::Mesh);
        for (uint32_t k = 0; k < t.triangles.size(); ++k) {
            const auto& tri = t.triangles[k];
            sites[t.face_id[k]] = {c, k, {t.vertex_id[tri[0]], t.vertex_id[tri[1]], t.vertex_id[tri[2]]}};
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
        size_t dropped = 0;
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
            p["chart"] = s.chart;
            p["triangle"] = s.triangle;
            p["barycentric"] = bary;
            p["vertex_ids"] = s.vertex;
            kept.push_back(std::move(p));
        }
        std::fprintf(stderr, "%zu points re-addressed, %zu dropped\n", kept.size(), dropped);
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
