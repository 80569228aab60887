// OpenEXR scanline output through a seekable file descriptor we own (so the temporary +
// rename discipline of every mebake output applies), and a small reader for tests. ZIP
// files (the default) have their chunks compressed here, in parallel, as OpenEXR would.
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
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <half.h>
#include <set>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

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

// OpenEXR's ZIP_COMPRESSION holds 16 scanlines per chunk.
constexpr int kZipLines = 16;
static_assert(std::endian::native == std::endian::little,
              "ZIP chunks are laid out from memory as EXR's little-endian values");

void CheckedValue(float v, Imath::half* out) {
    CHECK(std::isfinite(v));
    *out = Imath::half(std::clamp(v, -kHalfMax, kHalfMax));
}
void CheckedValue(float v, float* out) {
    CHECK(std::isfinite(v));
    *out = v;
}

// One chunk's scanlines as OpenEXR stores them before compression: line by line, each
// channel's values in a run, channels in name order; little-endian halves or floats (as
// x86's memory is). `order` lists pixel-major channel indices in the file's name order.
template <class T>
void LayOutLines(const float* pixels, int width, int lines, std::span<const size_t> order,
                 std::vector<char>& raw) {
    const size_t nc = order.size(), w = size_t(width);
    raw.resize(size_t(lines) * nc * w * sizeof(T));
    T* out = reinterpret_cast<T*>(raw.data());
    for (int y = 0; y < lines; ++y) {
        const float* row = pixels + size_t(y) * w * nc;
        for (size_t k : order)
            for (size_t x = 0; x < w; ++x)
                CheckedValue(row[x * nc + k], out++);
    }
}

// Compresses a chunk exactly as OpenEXR 3's Zip class does (ImfZip.cpp): the bytes split
// into even and odd halves, each byte replaced by its difference from the one before
// (+128), then zlib's compress2 at the file's level. `packed` gets what the chunk stores:
// the compressed bytes, or `raw` itself when compressing does not make it smaller (as
// OpenEXR's line buffers fall back to). False when zlib fails.
bool ZipChunk(const std::vector<char>& raw, int level, std::vector<unsigned char>& tmp,
              std::vector<unsigned char>& packed) {
    const size_t n = raw.size();
    tmp.resize(n);
    size_t even = 0, odd = (n + 1) / 2;
    for (size_t i = 0; i < n; ++i)
        tmp[(i & 1) ? odd++ : even++] = static_cast<unsigned char>(raw[i]);
    for (size_t i = n; i-- > 1;)
        tmp[i] = static_cast<unsigned char>(int(tmp[i]) - int(tmp[i - 1]) + (128 + 256));
    uLongf size = compressBound(uLong(n));
    packed.resize(size);
    if (compress2(packed.data(), &size, tmp.data(), uLong(n), level) != Z_OK)
        return false;
    if (size < n)
        packed.resize(size);
    else
        packed.assign(raw.begin(), raw.end());
    return true;
}

void PutLe(std::vector<unsigned char>& out, uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i)
        out.push_back(static_cast<unsigned char>(v >> (8 * i)));
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
    std::unique_ptr<Imf::OutputFile> file;  // null when the chunks are written here
    std::vector<float> scratch;
    std::vector<Imath::half> half_scratch;
    int rows = 0;
    bool committed = false;

    // ZIP: OpenEXR writes the header and an empty offset table, then the chunks are
    // compressed here in parallel (OpenEXR's writePixels compresses on the calling thread
    // without its own pool) and written in order; Commit() fills the table.
    int zip_level = 0;
    uint64_t table_at = 0;             // file offset of the chunk offset table
    std::vector<uint64_t> offsets;     // of the chunks written
    std::vector<size_t> order;         // pixel-major channel index, in the file's order
    std::vector<float> pending;        // rows not yet making a whole chunk
    int pending_rows = 0;
    struct Chunk {  // one chunk's buffers, kept for the next call (no page faults per band)
        std::vector<char> raw;
        std::vector<unsigned char> tmp, packed;
    };
    std::vector<Chunk> chunk_buffers;

    void WriteChunks(const float* pixels, int lines);

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
    if (options.compression == ExrCompression::Zip) {
        // OpenEXR has written the magic number, the header and a zero offset table (one
        // entry per chunk) and leaves the stream after them; closing it now only writes
        // that table again.
        const uint64_t chunks = uint64_t((height + kZipLines - 1) / kZipLines);
        const uint64_t end = m.stream->tellp();
        CHECK_GT(end, 8 * chunks);
        m.table_at = end - 8 * chunks;
        m.zip_level = h.zipCompressionLevel();
        m.file.reset();
        if (!m.stream->error.empty())
            IoError({m.path}, "write failed: {}", m.stream->error);
        m.stream->seekp(end);
        for (auto it = h.channels().begin(); it != h.channels().end(); ++it)
            m.order.push_back(size_t(
                std::find(m.channels.begin(), m.channels.end(), it.name()) - m.channels.begin()));
        CHECK_EQ(m.order.size(), m.channels.size());
    }
}

void ExrWriter::Impl::WriteChunks(const float* pixels, int lines) {
    const int chunks = (lines + kZipLines - 1) / kZipLines;
    const size_t row_floats = size_t(width) * channels.size();
    if (chunk_buffers.size() < size_t(chunks))
        chunk_buffers.resize(size_t(chunks));
    std::vector<Chunk>& out = chunk_buffers;
    const bool half = options.type == ExrPixelType::Half;
    ParallelFor(0, chunks, [&](int64_t c) {
        const int first = int(c) * kZipLines, n = std::min(kZipLines, lines - first);
        const float* at = pixels + size_t(first) * row_floats;
        Chunk& k = out[size_t(c)];
        if (half)
            LayOutLines<Imath::half>(at, width, n, order, k.raw);
        else
            LayOutLines<float>(at, width, n, order, k.raw);
        if (!ZipChunk(k.raw, zip_level, k.tmp, k.packed))
            IoError({path}, "EXR chunk compression (zlib) failed");
    });
    std::vector<unsigned char> head;
    for (int c = 0; c < chunks; ++c) {
        const std::vector<unsigned char>& data = out[size_t(c)].packed;
        offsets.push_back(stream->tellp());
        head.clear();
        PutLe(head, uint64_t(uint32_t(rows + c * kZipLines)), 4);  // first line, int32
        PutLe(head, data.size(), 4);                               // bytes, int32
        stream->write(reinterpret_cast<const char*>(head.data()), int(head.size()));
        stream->write(reinterpret_cast<const char*>(data.data()), int(data.size()));
    }
}

ExrWriter::~ExrWriter() = default;

int ExrWriter::rows_written() const {
    return impl_->rows + impl_->pending_rows;
}
const std::string& ExrWriter::path() const {
    return impl_->path;
}

void ExrWriter::WriteRows(std::span<const float> pixels, int rows) {
    Impl& m = *impl_;
    CHECK(!m.committed);
    CHECK_GE(rows, 0);
    CHECK_LE(m.rows + m.pending_rows + rows, m.height);
    const size_t nc = m.channels.size();
    CHECK_EQ(pixels.size(), size_t(rows) * size_t(m.width) * nc);
    if (rows == 0)
        return;
    if (!m.file) {
        // Whole chunks go out now, from the caller's rows where no earlier rows wait;
        // the rest waits for the next call (or Commit(), the last chunk's short end).
        const size_t row_floats = size_t(m.width) * nc;
        if (m.pending_rows > 0) {
            const int take = std::min(rows, kZipLines - m.pending_rows);
            m.pending.insert(m.pending.end(), pixels.begin(),
                             pixels.begin() + ptrdiff_t(size_t(take) * row_floats));
            m.pending_rows += take;
            pixels = pixels.subspan(size_t(take) * row_floats);
            rows -= take;
            if (m.pending_rows < kZipLines)
                return;
            m.WriteChunks(m.pending.data(), kZipLines);
            m.rows += kZipLines;
            m.pending.clear();
            m.pending_rows = 0;
        }
        const int whole = rows / kZipLines * kZipLines;
        if (whole > 0) {
            m.WriteChunks(pixels.data(), whole);
            m.rows += whole;
        }
        m.pending.assign(pixels.begin() + ptrdiff_t(size_t(whole) * row_floats), pixels.end());
        m.pending_rows = rows - whole;
        return;
    }
    // OpenEXR does not convert between a slice's type and the file's when writing.
    const bool half = m.options.type == ExrPixelType::Half;
    const size_t elem = half ? sizeof(Imath::half) : sizeof(float);
    char* data;
    if (half) {
        // In parallel (PIZ or no compression: ZIP chunks convert in their own tasks).
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
    CHECK(!m.committed);
    if (m.file) {
        CHECK_EQ(m.rows, m.height);
        m.file.reset();
    } else {
        if (m.pending_rows > 0) {
            m.WriteChunks(m.pending.data(), m.pending_rows);
            m.rows += m.pending_rows;
            m.pending_rows = 0;
        }
        CHECK_EQ(m.rows, m.height);
        std::vector<unsigned char> table;
        for (uint64_t at : m.offsets)
            PutLe(table, at, 8);
        m.stream->seekp(m.table_at);
        m.stream->write(reinterpret_cast<const char*>(table.data()), int(table.size()));
    }
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
