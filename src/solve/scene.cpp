#include "solve/scene.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/log.h"
#include "io/mtl_reader.h"
#include "stream/ground.h"

namespace mebake::solve {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// The .mtl libraries an OBJ names, resolved next to the OBJ; a path that does not
// exist as written is also tried by file name alone (files often move without them).
std::vector<io::MtlMaterial> LoadMtls(const stream::InputRecord& in) {
    std::vector<io::MtlMaterial> all;
    if (in.path == "-") return all;
    fs::path base = fs::path(in.path).parent_path();
    for (const auto& lib : in.mtllibs) {
        fs::path p = base / lib;
        if (!fs::exists(p)) p = base / fs::path(lib).filename();
        if (!fs::exists(p)) {
            spdlog::warn("{}: material library {} not found; default albedo used", in.path, lib);
            continue;
        }
        auto mats = io::ReadMtl(p.string());
        all.insert(all.end(), mats.begin(), mats.end());
    }
    return all;
}

Material FromMtl(const std::string& name, const std::vector<io::MtlMaterial>& lib) {
    Material m;
    m.name = name;
    for (const auto& t : lib) {
        if (t.name != name) continue;
        if (t.kd) m.albedo = *t.kd;
        if (t.ke) m.emission = *t.ke;
        // Some files mark emitters only by an ambient term above 1 (no real reflectance
        // is); take it as emission.
        if (!t.ke && t.ka && (t.ka->x > 1 || t.ka->y > 1 || t.ka->z > 1)) m.emission = *t.ka;
        if (t.ns && t.ks && (t.ks->x > 0 || t.ks->y > 0 || t.ks->z > 0)) {
            m.glossy_exponent = *t.ns;
            m.glossy_weight = std::max({t.ks->x, t.ks->y, t.ks->z});
        }
    }
    // Physical limit: energy conservation needs albedo < 1.
    for (int c = 0; c < 3; ++c) m.albedo[c] = std::clamp(m.albedo[c], 0.f, 0.99f);
    return m;
}

Vec3d ReadVec3(const json& j, const std::string& file, const std::string& field) {
    if (j.is_number()) {
        double v = j.get<double>();
        return {v, v, v};
    }
    if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() ||
        !j[2].is_number())
        InputError({file}, "{}: expected a number or an array of 3 numbers", field);
    Vec3d v{j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
    for (int c = 0; c < 3; ++c)
        if (!std::isfinite(v[c])) InputError({file}, "{}: not a finite number", field);
    return v;
}

void ApplyMaterialJson(Material& m, const json& j, const std::string& file, const std::string& at) {
    if (j.contains("albedo")) m.albedo = Vec3f(ReadVec3(j["albedo"], file, at + ".albedo"));
    if (j.contains("use_vertex_colors")) m.use_vertex_colors = j["use_vertex_colors"].get<bool>();
    if (j.contains("color_factor")) m.color_factor = j["color_factor"].get<float>();
    if (j.contains("emission")) m.emission = Vec3f(ReadVec3(j["emission"], file, at + ".emission"));
    if (j.contains("glossy_exponent")) m.glossy_exponent = j["glossy_exponent"].get<float>();
    if (j.contains("glossy_weight")) m.glossy_weight = j["glossy_weight"].get<float>();
    for (int c = 0; c < 3; ++c) {
        if (m.albedo[c] < 0 || m.albedo[c] >= 1)
            InputError({file}, "{}.albedo must lie in [0, 1)", at);
        if (m.emission[c] < 0) InputError({file}, "{}.emission must not be negative", at);
    }
}

}  // namespace

// The rig lights the object, not the ground plane --ground added around it.
static void AddObjectRig(Scene& scene, const stream::Manifest& m) {
    if (m.ground)
        AddDefaultRig(scene, m.object_bbox_min, m.object_bbox_max);
    else
        AddDefaultRig(scene, m.bbox_min, m.bbox_max);
}

void AddDefaultRig(Scene& scene, const Vec3d& bmin, const Vec3d& bmax) {
    Vec3d center = (bmin + bmax) * 0.5;
    double diag = std::max(Length(bmax - bmin), 1e-9);
    Vec3d up = scene.sky.up;
    // A uniform sky of radiance 1/pi... gives irradiance 1 on an open upward face.
    scene.sky.type = Sky::Type::Uniform;
    scene.sky.radiance = Vec3d(0.25, 0.27, 0.30);
    // Key light: a square of side diag/5, 1.5 diagonals away, from the side (the default
    // camera's right, output/render.cpp) and 40 degrees above the horizon: small and low
    // enough to cast shadows the camera sees, where one from near the camera would hide them.
    Vec3d side = std::abs(up.x) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 0, 1);
    Vec3d front = Normalize(Cross(side, up));
    side = Normalize(Cross(up, front));
    Vec3d dir = Normalize(up * 0.84 + side * 0.94 - front * 0.2);
    Vec3d c = center + dir * (1.5 * diag);
    // Axes of the square, perpendicular to dir; the light faces the centre.
    Vec3d a = Normalize(Cross(dir, up));
    Vec3d b = Cross(a, dir);
    double h = diag * 0.1;
    PolygonLight key;
    // Wound so its front normal a x b = -dir faces the centre.
    key.vertices = {c - a * h - b * h, c + a * h - b * h, c + a * h + b * h, c - a * h + b * h};
    // Radiance such that the irradiance at the centre is about 3 (key : fill = 3 : 1).
    double solid = (4 * h * h) / ((1.5 * diag) * (1.5 * diag));
    double l = 3.0 / solid;
    key.radiance = Vec3d(l, l * 0.97, l * 0.92);
    scene.lights.push_back(key);
}

namespace {

// The scene file's "lights": polygons with a radiance.
void ReadLights(const json& lights, const std::string& scene_file, std::vector<PolygonLight>* out) {
    int k = 0;
    for (const auto& l : lights) {
        std::string at = "lights[" + std::to_string(k++) + "]";
        std::string type = l.value("type", "polygon");
        if (type != "polygon")
            InputError({scene_file}, "{}.type '{}': only 'polygon' lights exist", at, type);
        PolygonLight pl;
        for (const auto& v : l.at("vertices"))
            pl.vertices.push_back(ReadVec3(v, scene_file, at + ".vertices"));
        if (pl.vertices.size() < 3 || pl.vertices.size() > 64)
            InputError({scene_file}, "{}.vertices: a polygon needs 3 to 64 vertices", at);
        pl.radiance = ReadVec3(l.at("radiance"), scene_file, at + ".radiance");
        pl.two_sided = l.value("two_sided", false);
        out->push_back(pl);
    }
}

// The scene file's "solver" settings, over the defaults in *o.
void ReadSolverSettings(const json& s, const std::string& scene_file, SolverSettings* o) {
    o->order = s.value("order", o->order);
    o->tolerance = s.value("tolerance", o->tolerance);
    o->max_bounces = s.value("max_bounces", o->max_bounces);
    o->stop_fraction = s.value("stop_fraction", o->stop_fraction);
    o->chart_stop_fraction = s.value("chart_stop_fraction", o->chart_stop_fraction);
    o->unshot_tail = s.value("unshot_tail", o->unshot_tail);
    o->sky_directions = s.value("sky_directions", o->sky_directions);
    o->light_samples = s.value("light_samples", o->light_samples);
    o->cluster_links = s.value("cluster_links", o->cluster_links);
    o->link_tolerance = s.value("link_tolerance", o->link_tolerance);
    o->link_size_error = s.value("link_size_error", o->link_size_error);
    if (!(o->link_size_error >= 0))
        InputError({scene_file}, "solver.link_size_error must be >= 0");
    o->sky_extra_levels = s.value("sky_extra_levels", o->sky_extra_levels);
    o->sky_fit_floor = s.value("sky_fit_floor", o->sky_fit_floor);
    o->emitter_texels = s.value("emitter_texels", o->emitter_texels);
    if (o->emitter_texels < 0 || o->emitter_texels > 64 ||
        (o->emitter_texels & (o->emitter_texels - 1)) != 0)
        InputError({scene_file}, "solver.emitter_texels must be 0 or a power of two up to 64");
    o->near_emitter_split = s.value("near_emitter_split", o->near_emitter_split);
    if (!(o->near_emitter_split >= 0))
        InputError({scene_file}, "solver.near_emitter_split must be >= 0");
    o->sky_deep_floor = s.value("sky_deep_floor", o->sky_deep_floor);
    o->outline_face_inside = s.value("outline_face_inside", o->outline_face_inside);
    o->light_probes_inherit = s.value("light_probes_inherit", o->light_probes_inherit);
    if (!(o->sky_deep_floor >= 0))
        InputError({scene_file}, "solver.sky_deep_floor must be >= 0");
    if (o->sky_extra_levels < 0 || o->sky_extra_levels > 8)
        InputError({scene_file}, "solver.sky_extra_levels must be 0..8");
    if (!(o->sky_fit_floor >= 0))
        InputError({scene_file}, "solver.sky_fit_floor must be >= 0");
    if (!(o->chart_stop_fraction >= 0 && o->chart_stop_fraction < 1))
        InputError({scene_file}, "solver.chart_stop_fraction must lie in [0, 1)");
    if (o->order < 0 || o->order > 3) InputError({scene_file}, "solver.order must be 0..3");
    const std::string multi =
        s.value("multi_emitter", std::string(o->multi_emitter_simplify ? "simplify" : "full"));
    if (multi != "full" && multi != "simplify")
        InputError({scene_file}, "solver.multi_emitter '{}': expected full or simplify", multi);
    o->multi_emitter_simplify = multi == "simplify";
}

}  // namespace

Scene LoadScene(const stream::Manifest& manifest, const std::string& scene_file) {
    Scene scene;
    scene.sky.up = manifest.up;  // the scene file's "up" overrides it
    for (const auto& in : manifest.inputs) {
        auto lib = LoadMtls(in);
        std::vector<Material> mats;
        if (in.materials.empty()) mats.push_back(FromMtl("", lib));
        for (const auto& name : in.materials) mats.push_back(FromMtl(name, lib));
        if (in.path == stream::kGroundSource)  // --ground: a neutral floor
            mats.front().albedo = Vec3f(stream::kGroundAlbedo, stream::kGroundAlbedo,
                                        stream::kGroundAlbedo);
        scene.per_input.push_back(std::move(mats));
    }
    bool any_emitter = false;
    for (auto& mats : scene.per_input)
        for (auto& m : mats) any_emitter |= m.emissive();

    if (scene_file.empty()) {
        scene.description = any_emitter ? "materials from the inputs (emissive materials light it)"
                                        : "default rig: uniform sky and a key area light";
        if (!any_emitter) AddObjectRig(scene, manifest);
        return scene;
    }

    std::ifstream f(scene_file);
    if (!f) IoError({scene_file}, "cannot open the scene file");
    json j;
    try {
        j = json::parse(f);
    } catch (const json::parse_error& e) {
        InputError({scene_file, uint64_t(e.byte)}, "malformed JSON: {}", e.what());
    }
    scene.description = "scene file " + scene_file;
    try {
        if (j.contains("up")) scene.sky.up = Normalize(ReadVec3(j["up"], scene_file, "up"));
        // Materials: each rule applies to faces of matching input index and/or name.
        if (j.contains("materials")) {
            int k = 0;
            for (const auto& rule : j["materials"]) {
                std::string at = "materials[" + std::to_string(k++) + "]";
                std::optional<size_t> input;
                std::optional<std::string> name;
                if (rule.contains("input")) input = rule["input"].get<size_t>();
                if (rule.contains("name")) name = rule["name"].get<std::string>();
                if (input && *input >= scene.per_input.size())
                    InputError({scene_file}, "{}.input = {} but there are only {} inputs", at,
                               *input, scene.per_input.size());
                for (size_t i = 0; i < scene.per_input.size(); ++i) {
                    if (input && *input != i) continue;
                    for (auto& m : scene.per_input[i])
                        if (!name || *name == m.name) ApplyMaterialJson(m, rule, scene_file, at);
                }
            }
        }
        if (j.contains("lights")) ReadLights(j["lights"], scene_file, &scene.lights);
        if (j.contains("sky")) {
            const auto& s = j["sky"];
            std::string type = s.value("type", "uniform");
            if (type == "uniform") scene.sky.type = Sky::Type::Uniform;
            else if (type == "overcast") scene.sky.type = Sky::Type::Overcast;
            else if (type == "none") scene.sky.type = Sky::Type::None;
            else InputError({scene_file}, "sky.type '{}': expected uniform, overcast or none", type);
            if (s.contains("radiance")) scene.sky.radiance = ReadVec3(s["radiance"], scene_file, "sky.radiance");
        }
        if (j.value("default_rig", false))
            AddObjectRig(scene, manifest);
        if (j.contains("solver")) ReadSolverSettings(j["solver"], scene_file, &scene.solver);
    } catch (const json::exception& e) {
        InputError({scene_file}, "{}", e.what());
    }
    return scene;
}

Vec3f SkyRadiance(const Sky& sky, const Vec3f& dir) {
    switch (sky.type) {
    case Sky::Type::Uniform:
        return Vec3f(sky.radiance);
    case Sky::Type::Overcast: {
        const float c = std::max(0.f, Dot(Normalize(dir), Vec3f(Normalize(sky.up))));
        return Vec3f(sky.radiance) * ((1 + 2 * c) / 3);
    }
    case Sky::Type::None:
        break;
    }
    return Vec3f{};
}

}  // namespace mebake::solve
