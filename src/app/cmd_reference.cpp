// `mebake reference`: path-traced B and E at random surface points (reference/reference.h), and
// `mebake compare`: the solved bake at the same points (output/probe.h) scored against them.
#include "app/reference_commands.h"
#include "core/error.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/units.h"
#include "io/byte_stream.h"
#include "output/bake_view.h"
#include "output/probe.h"
#include "reference/reference.h"
#include "solve/solution.h"
#include "stream/trimesh.h"

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>

namespace mebake::app {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json J(const Vec3d& v) {
    return json::array({v.x, v.y, v.z});
}
json J(const Vec3f& v) {
    return json::array({v.x, v.y, v.z});
}
json J(const Vec2f& v) {
    return json::array({v.x, v.y});
}

void WriteJson(const json& j, const std::string& path) {
    // Through io::OutputStream: a temporary renamed into place, or written straight to
    // stdout, a device or a FIFO (renaming over /dev/null would replace the device).
    auto out = io::OutputStream::Open(path);
    out->Write(j.dump(1) + "\n");
    out->Commit();
}

json ErrorJson(const output::ProbeError& e) {
    return {{"points", e.points},
            {"relative_rms", e.relative_rms},
            {"relative_max", e.relative_max},
            {"reference_noise_rms", e.noise_rms},
            {"corrected_rms", e.corrected_rms},
            {"median_relative", e.median_relative},
            {"mean_bake", e.mean_bake},
            {"mean_reference", e.mean_reference}};
}

Vec3d ReadVec3(const json& j, const std::string& file, size_t i, const char* key) {
    if (!j.contains(key) || !j[key].is_array() || j[key].size() != 3)
        InputError({file}, "point {}: '{}' must be an array of 3 numbers", i, key);
    Vec3d v;
    for (int k = 0; k < 3; ++k) {
        if (!j[key][size_t(k)].is_number())
            InputError({file}, "point {}: '{}' must be an array of 3 numbers", i, key);
        v[k] = j[key][size_t(k)].get<double>();
    }
    return v;
}

// The reference's vector irradiance per point ("E": 3 colours x 3 axes), or none when a
// point lacks it (an older reference).
std::vector<std::array<Vec3d, 3>> ReadIrradiance(const json& points, const std::string& file) {
    std::vector<std::array<Vec3d, 3>> e(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
        const json& p = points[i];
        if (!p.contains("E"))
            return {};
        const json& ej = p["E"];
        for (size_t c = 0; c < 3; ++c)
            for (size_t k = 0; k < 3; ++k) {
                if (!ej.is_array() || ej.size() != 3 || !ej[c].is_array() || ej[c].size() != 3 ||
                    !ej[c][k].is_number())
                    InputError({file}, "point {}: 'E' must be 3 arrays of 3 numbers", i);
                e[i][c][int(k)] = ej[c][k].get<double>();
            }
    }
    return e;
}

output::ProbeError Score(const output::BakeView& view, const std::vector<output::ProbeSite>& sites,
                        const std::vector<Vec3d>& ref, const std::vector<Vec3d>& se,
                        std::vector<output::ProbeValue>& values) {
    values = output::ProbeSolution(view, sites);
    std::vector<Vec3d> bake(values.size());
    for (size_t i = 0; i < values.size(); ++i)
        bake[i] = Vec3d(values[i].b);
    return output::CompareRadiosity(ref, se, bake);
}

}  // namespace

int RunReference(const ReferenceCommand& c) {
    if (!c.images.empty() || !c.rule_images.empty())
        return RunReferenceImage(c);
    if (!c.eye.empty() || !c.look_at.empty() || !c.up.empty())
        UsageError("reference: --eye, --target x,y,z and --up need --image");
    ThreadLimit limit(c.threads);
    const stream::Manifest m = stream::ReadManifest(c.dir);
    if (m.state != "ingested")
        UsageError("{}: ingest did not finish (state '{}')", c.dir, m.state);
    const bool solved = fs::exists(solve::SolutionPath(c.dir));
    // The scene: the one given, else the one the solve used (kept beside the solution).
    std::string scene_file = c.scene_file;
    if (scene_file.empty() && fs::exists(c.dir + "/solve/scene.json"))
        scene_file = c.dir + "/solve/scene.json";
    const solve::Scene scene = solve::LoadScene(m, scene_file);
    spdlog::info("reference: scene {}", scene.description);

    const reference::ReferenceMesh mesh = reference::LoadReferenceMesh(c.dir, m);
    spdlog::info("reference: {} triangles, {} points", FormatCount(double(mesh.triangles.size())),
                 c.points);
    std::vector<reference::ReferencePoint> points =
        reference::ChooseReferencePoints(mesh, scene, c.points, c.seed);
    const reference::ReferenceTracer tracer(mesh, scene);
    reference::ReferenceOptions opt;
    opt.seed = c.seed;
    opt.min_samples = c.min_samples;
    opt.max_samples = c.max_samples;
    opt.target_relative_error = c.target;
    opt.time_limit = c.time_limit;
    const reference::ReferenceStats st = tracer.Estimate(points, opt, [&](int round, uint64_t done) {
        spdlog::info("  round {}: {} of {} points converged", round, done, points.size());
    });
    spdlog::info("reference: {} paths, {} rays in {} ({})", FormatCount(double(st.paths)),
                 FormatCount(double(st.rays)), FormatSeconds(st.seconds), st.stop);

    json j;
    j["format"] = "mebake-reference-1";
    j["dir"] = c.dir;
    j["scene"] = scene_file.empty() ? "default" : scene_file;
    j["scene_description"] = scene.description;
    j["seed"] = c.seed;
    j["triangles"] = mesh.triangles.size();
    j["settings"] = {{"min_samples", c.min_samples},
                     {"max_samples", c.max_samples},
                     {"target_relative_error", c.target},
                     {"time_limit", c.time_limit}};
    j["stats"] = {{"rounds", st.rounds},   {"paths", st.paths},         {"rays", st.rays},
                  {"seconds", st.seconds}, {"converged", st.converged}, {"stop", st.stop}};
    std::vector<output::ProbeSite> sites;
    std::vector<Vec3d> ref, se;
    for (const auto& p : points) {
        sites.push_back({p.chart, p.local_triangle, p.barycentric});
        ref.push_back(p.b);
        se.push_back(p.b_se);
    }
    std::vector<output::ProbeValue> values;
    if (solved && c.scene_file.empty()) {
        const output::BakeView view = output::OpenBakeView(c.dir);
        const output::ProbeError e = Score(view, sites, ref, se, values);
        j["error"] = ErrorJson(e);
        spdlog::info(
            "bake vs reference: relative RMS {:.2f}% (reference noise {:.2f}%), max {:.1f}%",
            100 * e.relative_rms, 100 * e.noise_rms, 100 * e.relative_max);
    }
    json pts = json::array();
    for (size_t i = 0; i < points.size(); ++i) {
        const auto& p = points[i];
        json q = {{"chart", p.chart},
                  {"triangle", p.local_triangle},
                  {"barycentric", J(p.barycentric)},
                  {"uv", J(p.uv)},
                  {"face", p.face_id == stream::kNoId ? json(nullptr) : json(p.face_id)},
                  {"vertex_ids", json::array({p.vertex_ids[0], p.vertex_ids[1], p.vertex_ids[2]})},
                  {"position", J(p.position)},
                  {"normal", J(p.normal)},
                  {"albedo", J(p.albedo)},
                  {"samples", p.samples},
                  {"B", J(p.b)},
                  {"B_se", J(p.b_se)},
                  {"E", {J(p.e[0]), J(p.e[1]), J(p.e[2])}},
                  {"E_se", {J(p.e_se[0]), J(p.e_se[1]), J(p.e_se[2])}}};
        if (!values.empty()) {
            q["bake_B"] = J(values[i].b);
            q["bake_E"] = {J(values[i].e[0]), J(values[i].e[1]), J(values[i].e[2])};
        }
        pts.push_back(std::move(q));
    }
    j["points"] = std::move(pts);
    WriteJson(j, c.output);
    return 0;
}

int RunCompare(const CompareCommand& c) {
    if (IsPicturePair(c))
        return RunCompareImages(c);
    json r;
    {
        std::ifstream f(c.reference);
        if (!f)
            IoError({c.reference}, "cannot open");
        try {
            r = json::parse(f);
        } catch (const json::exception& e) {
            InputError({c.reference}, "not JSON: {}", e.what());
        }
    }
    if (!r.is_object() || r.value("format", "") != "mebake-reference-1" || !r.contains("points") ||
        !r["points"].is_array())
        InputError({c.reference}, "not a `mebake reference` output (format mebake-reference-1)");
    std::vector<output::ProbeSite> sites;
    std::vector<Vec3d> ref, se;
    for (size_t i = 0; i < r["points"].size(); ++i) {
        const json& p = r["points"][i];
        if (!p.is_object() || !p.contains("chart") || !p["chart"].is_number_unsigned() ||
            !p.contains("triangle") || !p["triangle"].is_number_unsigned())
            InputError({c.reference}, "point {}: needs unsigned 'chart' and 'triangle'", i);
        const uint64_t chart = p["chart"].get<uint64_t>(), tri = p["triangle"].get<uint64_t>();
        if (chart > 0xFFFFFFFFull || tri > 0xFFFFFFFFull)
            InputError({c.reference}, "point {}: chart or triangle out of range", i);
        sites.push_back(
            {uint32_t(chart), uint32_t(tri), Vec3f(ReadVec3(p, c.reference, i, "barycentric"))});
        ref.push_back(ReadVec3(p, c.reference, i, "B"));
        se.push_back(ReadVec3(p, c.reference, i, "B_se"));
    }
    const std::vector<std::array<Vec3d, 3>> ref_e = ReadIrradiance(r["points"], c.reference);
    const output::BakeView view =
        output::OpenBakeView(c.dir, output::FieldLoading::All,
                             c.no_stitch ? output::SeamStitching::Off : output::SeamStitching::On);
    std::vector<output::ProbeValue> values;
    const output::ProbeError e = Score(view, sites, ref, se, values);
    spdlog::info("bake vs reference: relative RMS {:.2f}% (reference noise {:.2f}%), max {:.1f}%",
                 100 * e.relative_rms, 100 * e.noise_rms, 100 * e.relative_max);
    json j;
    j["dir"] = c.dir;
    j["reference"] = c.reference;
    j["order"] = view.solution.fields.empty() ? -1 : view.solution.fields[0].order();
    j["error"] = ErrorJson(e);
    // The display rule with the reference's own E (docs/accuracy.md): what the light map's
    // representation loses at these points even with an exact field.
    std::vector<Vec3d> rule;
    if (!ref_e.empty() && !view.solution.radiosity) {
        for (size_t i = 0; i < values.size(); ++i)
            rule.push_back(output::DisplayRule(values[i], ref_e[i].data()));
        const output::ProbeError re = output::CompareRadiosity(ref, se, rule);
        spdlog::info("the display rule with the reference's E: relative RMS {:.2f}%",
                     100 * re.relative_rms);
        j["rule_error"] = ErrorJson(re);
    }
    if (c.points) {
        json pts = json::array();
        for (size_t i = 0; i < values.size(); ++i) {
            json p = {{"B", J(ref[i])}, {"bake_B", J(values[i].b)}};
            if (!rule.empty()) {
                p["rule_B"] = J(rule[i]);
                // Degrees between the shading normal and the face's: where the rule loses.
                const double cos_tilt =
                    std::clamp(double(Dot(values[i].normal, values[i].face_normal)), -1.0, 1.0);
                p["tilt"] = std::acos(cos_tilt) * 180 / std::numbers::pi;
            }
            pts.push_back(std::move(p));
        }
        j["points"] = std::move(pts);
    }
    WriteJson(j, c.output);
    return 0;
}

}  // namespace mebake::app
