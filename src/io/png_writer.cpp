// libpng reports errors by longjmp. Every libpng call sits in a function whose frame has
// a setjmp and no C++ object constructed after it; errors (libpng's, or an exception
// from our output stream, parked in the Impl) are turned into exceptions after the jump.
#include "io/png_writer.h"

#include "core/check.h"
#include "core/error.h"

#include <csetjmp>
#include <cstring>
#include <exception>
#include <png.h>
#include <zlib.h>

namespace mebake::io {

namespace {

struct ErrorState {
    char message[256] = {};
    std::exception_ptr pending;  // an exception from our I/O callback
};

void OnError(png_structp png, png_const_charp msg) {
    auto* s = static_cast<ErrorState*>(png_get_error_ptr(png));
    std::snprintf(s->message, sizeof(s->message), "%s", msg ? msg : "libpng error");
    png_longjmp(png, 1);
}

void OnWarning(png_structp, png_const_charp) {}

}  // namespace

struct PngWriter::Impl {
    OutputStream* out = nullptr;
    png_structp png = nullptr;
    png_infop info = nullptr;
    ErrorState error;
    int width = 0, height = 0, channels = 0, rows = 0;
    bool finished = false;

    ~Impl() {
        if (png)
            png_destroy_write_struct(&png, &info);
    }

    static void Write(png_structp png, png_bytep data, size_t n) {
        auto* self = static_cast<Impl*>(png_get_io_ptr(png));
        bool failed = false;
        try {
            self->out->Write(data, n);
        } catch (...) {
            self->error.pending = std::current_exception();
            failed = true;
        }
        if (failed)
            png_error(png, "output stream failed");
    }
    static void Flush(png_structp) {}

    [[noreturn]] void Fail() {
        if (error.pending)
            std::rethrow_exception(error.pending);
        IoError({out->name()}, "PNG encoding failed: {}", error.message);
    }

    // Each returns false after a libpng error.
    bool Start() {
        if (setjmp(png_jmpbuf(png)))
            return false;
        png_set_write_fn(png, this, &Impl::Write, &Impl::Flush);
        png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 8,
                     channels == 4 ? PNG_COLOR_TYPE_RGB_ALPHA : PNG_COLOR_TYPE_RGB,
                     PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
        // Deflate as run lengths over Paeth-filtered rows: a third of zlib's default CPU on
        // the light maps for +1-4 % of bytes (bench/RESULTS.md, issue 13, h-exp2); still
        // plain deflate, read by every PNG decoder.
        png_set_compression_strategy(png, Z_RLE);
        png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_PAETH);
        png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
        static char key[] = "Software", text[] = "mebake";
        png_text t{};
        t.compression = PNG_TEXT_COMPRESSION_NONE;
        t.key = key;
        t.text = text;
        png_set_text(png, info, &t, 1);
        png_write_info(png, info);
        return true;
    }
    bool Rows(const uint8_t* data, int count) {
        if (setjmp(png_jmpbuf(png)))
            return false;
        const size_t stride = size_t(width) * size_t(channels);
        for (int r = 0; r < count; ++r)
            png_write_row(png, const_cast<png_bytep>(data + r * stride));
        return true;
    }
    bool End() {
        if (setjmp(png_jmpbuf(png)))
            return false;
        png_write_end(png, info);
        return true;
    }
};

PngWriter::PngWriter(OutputStream& out, int width, int height, int channels)
    : impl_(std::make_unique<Impl>()) {
    CHECK(channels == 3 || channels == 4);
    CHECK(width >= 1 && width <= (1 << 20));
    CHECK(height >= 1 && height <= (1 << 20));
    Impl& m = *impl_;
    m.out = &out;
    m.width = width;
    m.height = height;
    m.channels = channels;
    m.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &m.error, OnError, OnWarning);
    if (!m.png)
        IoError({out.name()}, "libpng could not start (out of memory)");
    m.info = png_create_info_struct(m.png);
    if (!m.info)
        IoError({out.name()}, "libpng could not start (out of memory)");
    if (!m.Start())
        m.Fail();
}

PngWriter::~PngWriter() = default;

void PngWriter::WriteRows(std::span<const uint8_t> pixels, int rows) {
    Impl& m = *impl_;
    CHECK(!m.finished);
    CHECK_GE(rows, 0);
    CHECK_LE(m.rows + rows, m.height);
    CHECK_EQ(pixels.size(), size_t(rows) * size_t(m.width) * size_t(m.channels));
    if (!m.Rows(pixels.data(), rows))
        m.Fail();
    m.rows += rows;
}

void PngWriter::Finish() {
    Impl& m = *impl_;
    CHECK(!m.finished);
    CHECK_EQ(m.rows, m.height);
    if (!m.End())
        m.Fail();
    m.finished = true;
}

void WritePng(const std::string& path, int width, int height, int channels,
              std::span<const uint8_t> pixels) {
    auto out = OutputStream::Open(path);
    PngWriter w(*out, width, height, channels);
    w.WriteRows(pixels, height);
    w.Finish();
    out->Commit();
}

std::vector<uint8_t> EncodePng(int width, int height, int channels,
                               std::span<const uint8_t> pixels) {
    std::vector<uint8_t> bytes;
    auto out = OutputStream::ToMemory(&bytes);
    PngWriter w(*out, width, height, channels);
    w.WriteRows(pixels, height);
    w.Finish();
    out->Commit();
    return bytes;
}

namespace {

struct ReadState {
    std::span<const uint8_t> bytes;
    size_t pos = 0;
};

void ReadFn(png_structp png, png_bytep dst, size_t n) {
    auto* s = static_cast<ReadState*>(png_get_io_ptr(png));
    if (n > s->bytes.size() - s->pos)
        png_error(png, "truncated PNG");
    std::memcpy(dst, s->bytes.data() + s->pos, n);
    s->pos += n;
}

// Decodes into img; false after a libpng error (message in err).
bool Decode(png_structp png, png_infop info, ReadState* rs, PngImage* img,
            std::vector<png_bytep>* rows) {
    if (setjmp(png_jmpbuf(png)))
        return false;
    png_set_read_fn(png, rs, ReadFn);
    png_set_user_limits(png, 1u << 16, 1u << 16);
    png_read_info(png, info);
    png_set_expand(png);
    png_set_strip_16(png);
    png_set_gray_to_rgb(png);
    png_read_update_info(png, info);
    img->width = int(png_get_image_width(png, info));
    img->height = int(png_get_image_height(png, info));
    img->channels = int(png_get_channels(png, info));
    img->srgb = png_get_valid(png, info, PNG_INFO_sRGB) != 0;
    if (img->channels != 3 && img->channels != 4)
        png_error(png, "unexpected channel count");
    const size_t stride = png_get_rowbytes(png, info);
    img->pixels.resize(stride * size_t(img->height));
    rows->resize(size_t(img->height));
    for (int y = 0; y < img->height; ++y)
        (*rows)[size_t(y)] = img->pixels.data() + size_t(y) * stride;
    png_read_image(png, rows->data());
    png_read_end(png, nullptr);
    return true;
}

}  // namespace

PngImage DecodePng(std::span<const uint8_t> bytes, const std::string& name) {
    if (bytes.size() < 8 || png_sig_cmp(bytes.data(), 0, 8) != 0)
        InputError({name, 0}, "not a PNG file (bad signature)");
    ErrorState err;
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &err, OnError, OnWarning);
    if (!png)
        IoError({name}, "libpng could not start (out of memory)");
    png_infop info = png_create_info_struct(png);
    ReadState rs{bytes, 0};
    PngImage img;
    std::vector<png_bytep> rows;
    const bool ok = info && Decode(png, info, &rs, &img, &rows);
    png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
    if (!ok)
        InputError({name, rs.pos}, "cannot decode PNG: {}", err.message);
    return img;
}

PngImage ReadPng(const std::string& path) {
    return DecodePng(ReadWholeFile(path), path == "-" ? "<stdin>" : path);
}

}  // namespace mebake::io
