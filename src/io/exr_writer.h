// OpenEXR output (https://openexr.com): scanline images of any number of named float
// channels, stored as half or float, ZIP or PIZ compressed, written band by band so a
// large light-map page never has to be held in memory whole.
//
// Channel names follow the EXR convention "layer.channel": "R", "G", "B", "A" for a
// colour image; mebake's vector irradiance maps use "E.x.R", "E.x.G", "E.x.B", "E.y.R",
// ... (layer E.x holds the x component of E for the three colours, the seed paper's
// "three textures storing (x, y, z) in R, G, B"). EXR files list channels sorted by
// name whatever order they were given in; readers look them up by name.
//
// Every file carries the string attributes "software" = "mebake" and "comments" (what
// the pixels are), plus any the caller adds. The file is written to a temporary beside
// the target and renamed into place by Commit(); "-" writes to stdout (through an
// unlinked temporary, because the EXR line-offset table is written last and needs a
// seekable file), and a device or FIFO likewise (so /dev/null stays a device). Half
// channels saturate at +-65504 instead of becoming infinite.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace mebake::io {

enum class ExrPixelType { Half, Float };
enum class ExrCompression { None, Zip, Piz };

struct ExrOptions {
    ExrPixelType type = ExrPixelType::Half;
    ExrCompression compression = ExrCompression::Zip;
    std::string comments;  // the standard "comments" attribute: what the pixels hold
    std::vector<std::pair<std::string, std::string>> attributes;  // extra string attributes
};

class ExrWriter {
public:
    // Opens the output; throws Error(Io) naming the path. width, height >= 1 and the
    // channel names must be distinct and non-empty (CHECKed: they come from code).
    ExrWriter(std::string path, int width, int height, std::vector<std::string> channels,
              const ExrOptions& options = {});
    // Without Commit() the temporary is removed and `path` is left untouched.
    ~ExrWriter();
    ExrWriter(const ExrWriter&) = delete;
    ExrWriter& operator=(const ExrWriter&) = delete;

    // Appends `rows` rows, top to bottom: rows * width * channels floats, pixel-major
    // (pixel (x, y) channel k at (y * width + x) * channels + k, y counted from the first
    // row of this call). Values must be finite (CHECKed).
    void WriteRows(std::span<const float> pixels, int rows);
    // After the last row: finishes the file and moves it into place.
    void Commit();

    int rows_written() const;
    const std::string& path() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The whole image at once: width * height * channels floats, pixel-major.
void WriteExr(const std::string& path, int width, int height,
              const std::vector<std::string>& channels, std::span<const float> pixels,
              const ExrOptions& options = {});

// An EXR read back as floats (tests, tools): channels in the file's order.
struct ExrImage {
    int width = 0, height = 0;
    std::vector<std::string> channels;
    std::vector<bool> half;     // per channel: stored as half
    std::vector<float> pixels;  // pixel-major, channels.size() per pixel
    std::string compression;    // "none", "zip", "piz", "other"
    std::vector<std::pair<std::string, std::string>> string_attributes;

    // Index of a channel by name, -1 when absent.
    int Channel(const std::string& name) const;
    float At(int x, int y, int channel) const {
        return pixels[(size_t(y) * size_t(width) + size_t(x)) * channels.size() + size_t(channel)];
    }
};
// Throws Error(Io) when missing, Error(Input) naming the file when it is not a readable
// scanline EXR or larger than `max_pixels`.
ExrImage ReadExr(const std::string& path, uint64_t max_pixels = uint64_t(1) << 28);

}  // namespace mebake::io
