// OpenEXR scanline output through a seekable file descriptor we own (so the temporary +
// rename discipline of every mebake output applies), and a small reader for tests.
#include "io/exr_writer.h"

#include "core/check.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/temp_file.h"
#include "io/byte_stream.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <half.h>
#include <set>
#include <sys/stat.h>
#include <unistd.h>

namespace mebake::io {

namespace {

constexpr float kHalfMax = 65504.0f;

// Imf::OStream over a file descriptor, writing with pwrite at the stream position.
// OpenEXR swallows exceptions thrown while its destructor writes the offset table, so
// failures are also remembered in `error`.
class FdOStream final : public Imf::OStream {
public:
    FdOStream(int fd, const std::string& name) : Imf::OStream(name.c_str()), fd_(fd) {}

    void write(const char c[], int n) override {
        size_t left = size_t(n);
        while (left > 0) {
            ssize_t k = ::pwrite(fd_, c, left, off_t(pos_));
            if (k < 0 && errno == EINTR)
                continue;
            if (k <= 0) {
                error = k < 0 ? ErrnoString(errno) : std::string("nothing written");
                IoError({fileName()}, "write failed: {}", error);
            }
            c += k;
            left -= size_t(k);
            pos_ += uint64_t(k);
        }
    }
    uint64_t tellp() override { return pos_; }
    void seekp(uint64_t pos) override { pos_ = pos; }

    std::string error;

private:
    int fd_;
    uint64_t pos_ = 0;
};

Imf::Compression ToImf(ExrCompression c) {
    switch (c) {
    case ExrCompression::None:
        return Imf::NO_COMPRESSION;
    case ExrCompression::Piz:
        return Imf::PIZ_COMPRESSION;
    case ExrCompression::Zip:
        break;
    }
    return Imf::ZIP_COMPRESSION;
}

}  // namespace

struct ExrWriter::Impl {
    std::string path, temp;
    int fd = -1;
    bool to_stream = false;  // stdout, a device or a FIFO: copied there at Commit()
    int width = 0, height = 0;
    std::vector<std::string> channels;
    ExrOptions options;
    std::unique_ptr<FdOStream> stream;
    std::unique_ptr<Imf::OutputFile> file;
    std::vector<float> scratch;
    std::vector<Imath::half> half_scratch;
    int rows = 0;
    bool committed = false;

    ~Impl() {
        file.reset();  // writes the offset table (errors ignored: we are giving up)
        if (fd >= 0)
            ::close(fd);
        if (!committed && !temp.empty())
            ::unlink(temp.c_str());
    }
};

ExrWriter::ExrWriter(std::string path, int width, int height, std::vector<std::string> channels,
                     const ExrOptions& options)
    : impl_(std::make_unique<Impl>()) {
    CHECK_GE(width, 1);
    CHECK_GE(height, 1);
    CHECK(!channels.empty());
    std::set<std::string> unique(channels.begin(), channels.end());
    CHECK_EQ(unique.size(), channels.size());
    CHECK(!unique.count(""));
    Impl& m = *impl_;
    m.path = std::move(path);
    m.width = width;
    m.height = height;
    m.channels = std::move(channels);
    m.options = options;
    struct stat st {};
    // "-", /dev/null or a named pipe: a temporary renamed over a device would replace it
    // with a regular file, and OpenEXR needs a seekable file anyway: write an unlinked
    // temporary and copy it to the stream at the end.
    m.to_stream = m.path == "-" || (::stat(m.path.c_str(), &st) == 0 && !S_ISREG(st.st_mode));
    if (m.to_stream) {
        if (S_ISDIR(st.st_mode))
            IoError({m.path}, "is a directory, expected an output file");
        m.fd = OpenTemporaryFile(TemporaryDirectory(), "EXR image");
    } else {
        std::filesystem::path p(m.path);
        std::string dir = p.has_parent_path() ? p.parent_path().string() : ".";
        std::string tmpl = dir + "/." + p.filename().string() + ".tmp-XXXXXX";
        std::vector<char> name(tmpl.begin(), tmpl.end());
        name.push_back('\0');
        m.fd = ::mkostemp(name.data(), O_CLOEXEC);
        if (m.fd < 0)
            IoError({m.path}, "cannot create output: {}", ErrnoString(errno));
        m.temp = name.data();
        ::fchmod(m.fd, 0644);
    }

    Imf::Header h(width, height);
    h.compression() = ToImf(options.compression);
    const Imf::PixelType type = options.type == ExrPixelType::Half ? Imf::HALF : Imf::FLOAT;
    for (const auto& c : m.channels)
        h.channels().insert(c, Imf::Channel(type));
    h.insert("software", Imf::StringAttribute("mebake"));
    if (!options.comments.empty())
        h.insert("comments", Imf::StringAttribute(options.comments));
    for (const auto& [key, value] : options.attributes)
        h.insert(key, Imf::StringAttribute(value));
    m.stream = std::make_unique<FdOStream>(m.fd, m.path == "-" ? "<stdout>" : m.path);
    try {
        // No OpenEXR worker threads: TBB is mebake's only thread pool.
        m.file = std::make_unique<Imf::OutputFile>(*m.stream, h, 0);
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        IoError({m.path}, "cannot start the EXR file: {}", e.what());
    }
}

ExrWriter::~ExrWriter() = default;

int ExrWriter::rows_written() const {
    return impl_->rows;
}
const std::string& ExrWriter::path() const {
    return impl_->path;
}

void ExrWriter::WriteRows(std::span<const float> pixels, int rows) {
    Impl& m = *impl_;
    CHECK(m.file);
    CHECK_GE(rows, 0);
    CHECK_LE(m.rows + rows, m.height);
    const size_t nc = m.channels.size();
    CHECK_EQ(pixels.size(), size_t(rows) * size_t(m.width) * nc);
    if (rows == 0)
        return;
    // OpenEXR does not convert between a slice's type and the file's when writing.
    const bool half = m.options.type == ExrPixelType::Half;
    const size_t elem = half ? sizeof(Imath::half) : sizeof(float);
    char* data;
    if (half) {
        // In parallel: the ZIP stream after it is one thread's (a light map band's
        // conversion was a sixth of its EXR time, bench/RESULTS.md "Issue 13 (session 20)").
        m.half_scratch.resize(pixels.size());
        ParallelForRange(
            0, int64_t(pixels.size()),
            [&](int64_t lo, int64_t hi) {
                for (size_t i = size_t(lo); i < size_t(hi); ++i) {
                    CHECK(std::isfinite(pixels[i]));
                    m.half_scratch[i] = Imath::half(std::clamp(pixels[i], -kHalfMax, kHalfMax));
                }
            },
            int64_t(1) << 16);
        data = reinterpret_cast<char*>(m.half_scratch.data());
    } else {
        m.scratch.assign(pixels.begin(), pixels.end());
        for (float v : m.scratch)
            CHECK(std::isfinite(v));
        data = reinterpret_cast<char*>(m.scratch.data());
    }
    const size_t xs = nc * elem, ys = xs * size_t(m.width);
    // OpenEXR addresses pixel (x, y) at base + x * xs + y * ys with y the absolute row.
    char* origin = data - ptrdiff_t(size_t(m.rows) * ys);
    const Imf::PixelType type = half ? Imf::HALF : Imf::FLOAT;
    Imf::FrameBuffer fb;
    for (size_t k = 0; k < nc; ++k)
        fb.insert(m.channels[k], Imf::Slice(type, origin + k * elem, xs, ys));
    try {
        m.file->setFrameBuffer(fb);
        m.file->writePixels(rows);
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        IoError({m.path}, "EXR write failed: {}", e.what());
    }
    m.rows += rows;
}

void ExrWriter::Commit() {
    Impl& m = *impl_;
    CHECK(m.file);
    CHECK_EQ(m.rows, m.height);
    m.file.reset();
    if (!m.stream->error.empty())
        IoError({m.path}, "write failed: {}", m.stream->error);
    if (m.to_stream) {
        auto out = OutputStream::Open(m.path);
        std::vector<char> buf(size_t(1) << 20);
        off_t at = 0;
        for (;;) {
            ssize_t n = ::pread(m.fd, buf.data(), buf.size(), at);
            if (n < 0 && errno == EINTR)
                continue;
            if (n < 0)
                IoError({m.path}, "cannot read back the EXR temporary: {}", ErrnoString(errno));
            if (n == 0)
                break;
            out->Write(buf.data(), size_t(n));
            at += n;
        }
        out->Commit();
    } else {
        if (::fsync(m.fd) != 0)
            IoError({m.path}, "fsync failed: {}", ErrnoString(errno));
        if (::rename(m.temp.c_str(), m.path.c_str()) != 0)
            IoError({m.path}, "cannot rename the finished output into place: {}",
                    ErrnoString(errno));
    }
    m.committed = true;
}

void WriteExr(const std::string& path, int width, int height,
              const std::vector<std::string>& channels, std::span<const float> pixels,
              const ExrOptions& options) {
    ExrWriter w(path, width, height, channels, options);
    w.WriteRows(pixels, height);
    w.Commit();
}

int ExrImage::Channel(const std::string& name) const {
    for (size_t k = 0; k < channels.size(); ++k)
        if (channels[k] == name)
            return int(k);
    return -1;
}

ExrImage ReadExr(const std::string& path, uint64_t max_pixels) {
    if (!std::filesystem::exists(path))
        IoError({path}, "no such file");
    ExrImage img;
    try {
        Imf::InputFile file(path.c_str(), 0);
        const Imf::Header& h = file.header();
        const Imath::Box2i dw = h.dataWindow();
        const int64_t w = int64_t(dw.max.x) - dw.min.x + 1, ht = int64_t(dw.max.y) - dw.min.y + 1;
        if (w <= 0 || ht <= 0 || uint64_t(w) * uint64_t(ht) > max_pixels)
            InputError({path}, "data window {} x {} is empty or too large", w, ht);
        img.width = int(w);
        img.height = int(ht);
        for (auto it = h.channels().begin(); it != h.channels().end(); ++it) {
            img.channels.push_back(it.name());
            img.half.push_back(it.channel().type == Imf::HALF);
        }
        switch (h.compression()) {
        case Imf::NO_COMPRESSION:
            img.compression = "none";
            break;
        case Imf::ZIP_COMPRESSION:
            img.compression = "zip";
            break;
        case Imf::PIZ_COMPRESSION:
            img.compression = "piz";
            break;
        default:
            img.compression = "other";
            break;
        }
        for (auto it = h.begin(); it != h.end(); ++it)
            if (auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
                img.string_attributes.emplace_back(it.name(), s->value());
        const size_t nc = img.channels.size();
        img.pixels.assign(size_t(w) * size_t(ht) * nc, 0.f);
        const size_t xs = nc * sizeof(float), ys = xs * size_t(w);
        char* origin = reinterpret_cast<char*>(img.pixels.data()) -
                       ptrdiff_t(int64_t(dw.min.x) * int64_t(xs) + int64_t(dw.min.y) * int64_t(ys));
        Imf::FrameBuffer fb;
        for (size_t k = 0; k < nc; ++k)
            fb.insert(img.channels[k], Imf::Slice(Imf::FLOAT, origin + k * sizeof(float), xs, ys));
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        InputError({path}, "not a readable OpenEXR file: {}", e.what());
    }
    return img;
}

}  // namespace mebake::io
