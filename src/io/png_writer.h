// 8-bit sRGB PNG output with libpng (http://www.libpng.org), row by row, into any
// io::OutputStream (a file, stdout, or memory for embedding in a .glb). The file is
// tagged with an sRGB chunk (plus the matching gAMA/cHRM for old readers) and a
// "Software" text chunk; pixels must already be sRGB-encoded (output/tonemap.h does it).
#pragma once

#include "io/byte_stream.h"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace mebake::io {

class PngWriter {
public:
    // Writes the header to `out` at once. channels: 3 (RGB) or 4 (RGBA); width and height
    // in [1, 2^20] (CHECKed: they come from code). The stream is not committed here.
    PngWriter(OutputStream& out, int width, int height, int channels);
    ~PngWriter();
    PngWriter(const PngWriter&) = delete;
    PngWriter& operator=(const PngWriter&) = delete;

    // Appends `rows` rows, top to bottom, width * channels bytes each, contiguous.
    void WriteRows(std::span<const uint8_t> pixels, int rows);
    // After the last row: writes the end of the image. Throws Error(Io) on write errors.
    void Finish();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// A whole image to a path ("-" = stdout), committed.
void WritePng(const std::string& path, int width, int height, int channels,
              std::span<const uint8_t> pixels);
// A whole image encoded in memory.
std::vector<uint8_t> EncodePng(int width, int height, int channels,
                               std::span<const uint8_t> pixels);

// A PNG decoded to 8-bit RGB or RGBA (tests, tools).
struct PngImage {
    int width = 0, height = 0, channels = 0;
    bool srgb = false;  // carries an sRGB chunk
    std::vector<uint8_t> pixels;
};
// Throws Error(Input) naming `name` when the bytes are not a PNG libpng can read.
PngImage DecodePng(std::span<const uint8_t> bytes, const std::string& name = "<memory>");
PngImage ReadPng(const std::string& path);

}  // namespace mebake::io
