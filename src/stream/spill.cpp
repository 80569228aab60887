#include "stream/spill.h"

#include <algorithm>
#include <cmath>

#include "core/check.h"
#include "core/error.h"

namespace mebake::stream {

class Spill::Sink : public io::MeshSink {
public:
    Sink(Spill& spill, size_t input) : spill_(spill), input_(input) {}

    void Begin(const io::MeshHeader& header) override {
        auto& in = spill_.result_.inputs[input_];
        in.has_colors = header.has_colors;
    }

    void Vertices(const io::VertexBatch& b) override {
        auto& r = spill_.result_;
        auto& in = r.inputs[input_];
        CHECK_EQ(b.first, in.vertex_count);
        spill_.vertices_->PushMany(b.position.data(), b.size());
        colors_.resize(b.size());
        for (size_t i = 0; i < b.size(); ++i) {
            const Vec3f& p = b.position[i];
            r.bbox_min = Min(r.bbox_min, Vec3d(p));
            r.bbox_max = Max(r.bbox_max, Vec3d(p));
            if (b.color.empty()) {
                colors_[i] = {0, 0, 0, 0};
            } else {
                auto q = [](float c) { return uint8_t(std::lround(std::clamp(c, 0.f, 1.f) * 255)); };
                colors_[i] = {q(b.color[i].x), q(b.color[i].y), q(b.color[i].z), 255};
            }
        }
        spill_.colors_->PushMany(colors_.data(), colors_.size());
        in.vertex_count += b.size();
        r.vertex_count += b.size();
    }

    void Faces(const io::FaceBatch& b) override {
        auto& r = spill_.result_;
        auto& in = r.inputs[input_];
        tris_.clear();
        io::Triangulate(b, tris_);
        // Per-triangle material: repeat each polygon's material for its triangles.
        faces_.clear();
        size_t t = 0;
        for (size_t f = 0; f < b.count(); ++f) {
            uint32_t local = b.material.empty() ? 0 : b.material[f];
            if (local > 0xFFFF)
                InputError({in.source}, "more than 65536 materials in one mesh");
            uint32_t mat = uint32_t(input_) << 16 | local;
            for (uint32_t k = 2; k < b.size[f]; ++k, ++t) {
                SpillFace sf{};
                for (int c = 0; c < 3; ++c) sf.v[c] = tris_[3 * t + size_t(c)] + in.first_vertex;
                sf.material = mat;
                faces_.push_back(sf);
            }
        }
        spill_.faces_->PushMany(faces_.data(), faces_.size());
        in.face_count += faces_.size();
        r.face_count += faces_.size();
    }

    void End(const io::MeshSummary& s) override {
        auto& in = spill_.result_.inputs[input_];
        in.bytes_read = s.bytes_read;
        in.materials = s.materials;
        in.mtllibs = s.mtllibs;
    }

private:
    Spill& spill_;
    size_t input_;
    std::vector<uint64_t> tris_;
    std::vector<SpillFace> faces_;
    std::vector<SpillColor> colors_;
};

Spill::Spill(const std::string& dir, size_t cache_bytes) {
    size_t each = std::max<size_t>(cache_bytes / 3, size_t(1) << 20);
    vertices_ = std::make_unique<DiskArray<Vec3f>>(VerticesPath(dir), true, each);
    colors_ = std::make_unique<DiskArray<SpillColor>>(ColorsPath(dir), true, each);
    faces_ = std::make_unique<DiskArray<SpillFace>>(FacesPath(dir), true, each);
}

Spill::~Spill() = default;

io::MeshSink& Spill::BeginInput(const std::string& source) {
    if (result_.inputs.size() >= 0xFFFF) UsageError("too many input meshes (at most 65535)");
    SpillInput in;
    in.source = source;
    in.first_vertex = result_.vertex_count;
    in.first_face = result_.face_count;
    result_.inputs.push_back(in);
    sink_ = std::make_unique<Sink>(*this, result_.inputs.size() - 1);
    return *sink_;
}

const SpillResult& Spill::Finish() {
    vertices_->Flush();
    colors_->Flush();
    faces_->Flush();
    return result_;
}

}  // namespace mebake::stream
