// Test helper for the OBJ/OFF/STL reader tests: a sink that keeps the whole mesh and
// checks the streaming contract of io/mesh_stream.h on every call.
#pragma once

#include "core/error.h"
#include "io/byte_stream.h"
#include "io/mesh_stream.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace mebake::io::testing {

struct Collected {
    MeshHeader header;
    MeshSummary summary;
    std::vector<Vec3f> position, normal, color;
    std::vector<float> alpha;
    std::vector<Vec2f> uv;
    std::vector<uint32_t> face_size;
    std::vector<uint64_t> index;
    std::vector<uint32_t> material;
    int begins = 0, ends = 0;
    size_t vertex_batches = 0, face_batches = 0;

    size_t faces() const { return face_size.size(); }
    // Corner k of polygon f (slow; tests only).
    uint64_t Corner(size_t f, size_t k) const {
        size_t at = 0;
        for (size_t i = 0; i < f; ++i)
            at += face_size[i];
        return index[at + k];
    }
};

// Checks that faces only name vertices already delivered: true for OBJ, OFF and STL.
class CollectSink : public MeshSink {
public:
    explicit CollectSink(Collected& c) : c_(c) {}

    void Begin(const MeshHeader& h) override {
        EXPECT_EQ(c_.begins, 0) << "Begin twice";
        ++c_.begins;
        c_.header = h;
    }
    void Vertices(const VertexBatch& b) override {
        EXPECT_EQ(c_.begins, 1) << "Vertices before Begin";
        EXPECT_EQ(c_.ends, 0);
        EXPECT_EQ(b.first, c_.position.size());
        EXPECT_GT(b.size(), 0u) << "empty vertex batch";
        auto same = [&](size_t n, bool on) {
            return on ? n == b.size() : n == 0;
        };
        EXPECT_TRUE(same(b.normal.size(), c_.header.has_normals));
        EXPECT_TRUE(same(b.color.size(), c_.header.has_colors));
        EXPECT_TRUE(same(b.alpha.size(), c_.header.has_alpha));
        EXPECT_TRUE(same(b.uv.size(), c_.header.has_uvs));
        c_.position.insert(c_.position.end(), b.position.begin(), b.position.end());
        c_.normal.insert(c_.normal.end(), b.normal.begin(), b.normal.end());
        c_.color.insert(c_.color.end(), b.color.begin(), b.color.end());
        c_.alpha.insert(c_.alpha.end(), b.alpha.begin(), b.alpha.end());
        c_.uv.insert(c_.uv.end(), b.uv.begin(), b.uv.end());
        ++c_.vertex_batches;
    }
    void Faces(const FaceBatch& b) override {
        EXPECT_EQ(c_.begins, 1) << "Faces before Begin";
        EXPECT_EQ(c_.ends, 0);
        EXPECT_EQ(b.first, c_.face_size.size());
        EXPECT_GT(b.count(), 0u) << "empty face batch";
        EXPECT_TRUE(b.material.empty() || b.material.size() == b.count());
        uint64_t corners = 0;
        for (uint32_t n : b.size) {
            EXPECT_GE(n, 3u);
            corners += n;
        }
        EXPECT_EQ(corners, b.index.size());
        for (uint64_t i : b.index) {
            if (i >= c_.position.size()) {
                ADD_FAILURE() << "face names vertex " << i << " before it was delivered ("
                              << c_.position.size() << " so far)";
                break;
            }
        }
        c_.face_size.insert(c_.face_size.end(), b.size.begin(), b.size.end());
        c_.index.insert(c_.index.end(), b.index.begin(), b.index.end());
        c_.material.insert(c_.material.end(), b.material.begin(), b.material.end());
        ++c_.face_batches;
    }
    void End(const MeshSummary& s) override {
        EXPECT_EQ(c_.begins, 1);
        EXPECT_EQ(c_.ends, 0);
        ++c_.ends;
        c_.summary = s;
        EXPECT_EQ(s.vertex_count, c_.position.size());
        EXPECT_EQ(s.face_count, c_.face_size.size());
        for (uint32_t m : c_.material) {
            if (m >= s.materials.size()) {
                ADD_FAILURE() << "material " << m << " of " << s.materials.size();
                break;
            }
        }
    }

private:
    Collected& c_;
};

using Reader = void (*)(InputStream&, MeshSink&, const ReadOptions&);

inline Collected ReadText(Reader reader, std::string_view text, const ReadOptions& opt = {},
                          const std::string& name = "test.txt") {
    Collected c;
    CollectSink sink(c);
    auto in =
        InputStream::FromMemory({reinterpret_cast<const uint8_t*>(text.data()), text.size()}, name);
    reader(*in, sink, opt);
    EXPECT_EQ(c.ends, 1);
    return c;
}

inline Collected ReadPath(Reader reader, const std::string& path, const ReadOptions& opt = {}) {
    Collected c;
    CollectSink sink(c);
    auto in = InputStream::Open(path);
    reader(*in, sink, opt);
    EXPECT_EQ(c.ends, 1);
    return c;
}

// The message of the mebake::Error the reader throws on `text`; "" (and a failure) if none.
inline std::string ErrorOf(Reader reader, std::string_view text,
                           const std::string& name = "bad.txt") {
    Collected c;
    CollectSink sink(c);
    auto in =
        InputStream::FromMemory({reinterpret_cast<const uint8_t*>(text.data()), text.size()}, name);
    try {
        reader(*in, sink, {});
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
        return e.what();
    }
    ADD_FAILURE() << "no error for input of " << text.size() << " bytes";
    return "";
}

inline std::string SharedData(const std::string& rel) {
    return std::string(MEBAKE_SHARED_DATA) + "/" + rel;
}

inline bool Exists(const std::string& path) {
    return std::ifstream(path).good();
}

inline std::string Slurp(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

}  // namespace mebake::io::testing
