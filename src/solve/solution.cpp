#include "solve/solution.h"

#include "core/check.h"
#include "core/error.h"
#include "io/chunk_file.h"

#include <cmath>
#include <cstring>

namespace mebake::solve {

using io::Tag;

namespace {
struct Header {
    uint32_t order, blocks, charts, radiosity;
};
}  // namespace

std::string SolutionPath(const std::string& dir) {
    return dir + "/solve/solution.bin";
}

std::vector<PackedNode> PackNodes(std::span<const QuadNode> nodes) {
    std::vector<PackedNode> out;
    out.reserve(nodes.size());
    for (const auto& n : nodes)
        out.push_back({n.first_child, n.level, n.i, n.j});
    return out;
}

std::vector<QuadNode> UnpackNodes(const std::vector<PackedNode>& packed, const std::string& path,
                                  uint32_t c) {
    std::vector<QuadNode> nodes(packed.size());
    for (size_t k = 0; k < packed.size(); ++k) {
        const auto& p = packed[k];
        if (p.first_child >= 0 &&
            (size_t(p.first_child) <= k || size_t(p.first_child) + 4 > packed.size()))
            CorruptError({path}, "chart {}: node {} has bad children", c, k);
        if (p.level > 30)
            CorruptError({path}, "chart {}: node {} level {}", c, k, p.level);
        nodes[k] = QuadNode{p.first_child, uint8_t(p.level), p.i, p.j};
    }
    return nodes;
}

uint64_t ReadSolutionKey(const std::string& path) {
    io::ChunkReader r(path, Tag("SOLN"), kSolutionVersion, kSolutionVersion);
    if (!r.Has(Tag("SKEY")))
        return 0;
    auto b = r.Read(Tag("SKEY"));
    uint64_t key = 0;
    if (b.size() != sizeof(key))
        CorruptError({path}, "SKEY chunk has the wrong size");
    std::memcpy(&key, b.data(), sizeof(key));
    return key;
}

void WriteSolution(const std::string& path, const std::vector<ChartField>& fields, bool radiosity,
                   uint64_t key) {
    io::ChunkWriter w(path, Tag("SOLN"), kSolutionVersion);
    Header h{uint32_t(fields.empty() ? 0 : fields[0].order()),
             uint32_t(fields.empty() ? 0 : fields[0].blocks()), uint32_t(fields.size()),
             radiosity ? 1u : 0u};
    w.Add(Tag("HEAD"), 0, {reinterpret_cast<const uint8_t*>(&h), sizeof(h)}, false);
    if (key != 0)
        w.Add(Tag("SKEY"), 0, {reinterpret_cast<const uint8_t*>(&key), sizeof(key)}, false);
    for (uint32_t c = 0; c < fields.size(); ++c) {
        const RegionPin pin = fields[c].Pin();
        w.AddArray(Tag("NODE"), c, PackNodes(fields[c].nodes()));
        w.AddArray(Tag("COEF"), c, fields[c].values());
    }
    w.Finish(true);
}

SolutionReader::SolutionReader(const std::string& path)
    : path_(path), reader_(path, Tag("SOLN"), kSolutionVersion, kSolutionVersion) {
    auto hb = reader_.Read(Tag("HEAD"));
    Header h{};
    if (hb.size() != sizeof(h))
        CorruptError({path}, "HEAD chunk has the wrong size");
    std::memcpy(&h, hb.data(), sizeof(h));
    if (h.order > 3 || (h.blocks != 3 && h.blocks != 9) || h.charts > (1u << 28))
        CorruptError({path}, "HEAD chunk is inconsistent");
    radiosity_ = h.radiosity != 0;
    order_ = int(h.order);
    blocks_ = int(h.blocks);
    charts_ = h.charts;
}

ChartField SolutionReader::Read(uint32_t c) const {
    CHECK_LT(c, charts_);
    auto packed = reader_.ReadArray<PackedNode>(Tag("NODE"), c);
    auto coef = reader_.ReadArray<float>(Tag("COEF"), c);
    ChartField f(order_, blocks_);
    std::vector<QuadNode> nodes = UnpackNodes(packed, path_, c);
    if (nodes.empty() || coef.size() != nodes.size() * size_t(f.stride()))
        CorruptError({path_}, "chart {}: {} coefficients for {} nodes", c, coef.size(),
                     nodes.size());
    for (float x : coef)
        if (!std::isfinite(x))
            CorruptError({path_}, "chart {}: non-finite coefficient", c);
    f.Assign(std::move(nodes), std::move(coef), {});  // values only: nothing shoots
    return f;
}

Solution ReadSolution(const std::string& path) {
    const SolutionReader r(path);
    Solution s;
    s.radiosity = r.radiosity();
    for (uint32_t c = 0; c < r.chart_count(); ++c)
        s.fields.push_back(r.Read(c));
    return s;
}

}  // namespace mebake::solve
