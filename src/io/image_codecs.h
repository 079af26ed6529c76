// The image file formats texgrad reads and writes, each through its reference library (libpng,
// libjpeg-turbo, OpenEXR, libtiff), behind one set of functions (private to the io module).
// image_io.cpp chooses the codec and checks names and extensions; a codec decodes bytes into
// texel order (file row 0, the top, becomes texel row height - 1) and encodes texel rows back.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "texgrad/io/image.h"

namespace texgrad::codec {

/// Bytes of a whole file, decoded from memory.
using Bytes = std::span<const unsigned char>;

/// Width and height of an image, in texels.
using Size = std::pair<int, int>;

/// Throws InvalidInputError / UnsupportedError naming `name` unless a declared image of
/// `width` x `height` texels and `channels` channels is one texgrad takes (1-4 channels, at most
/// 2^30 texels), before any pixel memory is allocated for it.
void checkDeclaredImage(int width, int height, int channels, const std::string& name);

/// A level's value: level * (1 / top) in float, the conversion texgrad has always used
/// (OpenImageIO's, bit for bit; not always level / top).
template <typename T>
float levelValue(T level) {
  constexpr float scale = 1.0f / static_cast<float>(std::numeric_limits<T>::max());
  return static_cast<float>(level) * scale;
}

/// A value stored as an integer level: clamped to [0, 1] (NaN as 0), rounded to the nearest.
template <typename T>
T quantised(float value) {
  constexpr float top = static_cast<float>(std::numeric_limits<T>::max());
  const float clamped = std::isnan(value) ? 0.0f : std::clamp(value, 0.0f, 1.0f);
  return static_cast<T>(std::lround(clamped * top));
}

/// The texel row that is row `y` of the file (top first).
inline const float* fileRow(const Image& image, int y) {
  return image.pixels.data() + image.index(0, image.height - 1 - y);
}

/// The texel row that is row `y` of the file (top first).
inline float* fileRow(Image& image, int y) {
  return image.pixels.data() + image.index(0, image.height - 1 - y);
}

/// File row `y` of `image` as integer levels of type T (uint8_t or uint16_t), into `to`.
template <typename T>
void quantiseRow(const Image& image, int y, T* to) {
  const float* from = fileRow(image, y);
  const size_t samples = static_cast<size_t>(image.width) * static_cast<size_t>(image.channels);
  for (size_t k = 0; k < samples; ++k) to[k] = quantised<T>(from[k]);
}

/// Integer levels of type T (native byte order) as file row `y` of `image`.
template <typename T>
void levelsToRow(const T* from, Image& image, int y) {
  float* to = fileRow(image, y);
  const size_t samples = static_cast<size_t>(image.width) * static_cast<size_t>(image.channels);
  for (size_t k = 0; k < samples; ++k) to[k] = levelValue(from[k]);
}

/// A file created for writing (by the C libraries' stdio interfaces); close() throws IoError
/// prefixed by `where` unless every byte reached it.
class OutputFile {
 public:
  OutputFile(const std::filesystem::path& path, const std::string& where);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  /// The open stream.
  std::FILE* get() const { return file_; }
  /// Flushes and closes the stream; throws IoError if a write or the close failed.
  void close();

 private:
  std::FILE* file_ = nullptr;
  std::string where_;
};

/// A codec's message on one line (texgrad's errors are one line); "unknown error" if empty.
std::string oneLine(std::string message);

// Decoding: `name` is used in messages; InvalidInputError for malformed or truncated content,
// UnsupportedError for valid files texgrad does not take. Nothing is printed.

/// Decodes a PNG (8 or 16 bits; palettes, low bit depths and tRNS expanded to grey/RGB(A)).
Image decodePng(Bytes bytes, const std::string& name);
/// Decodes a baseline or progressive JPEG (grey or colour; 8-bit). Any libjpeg warning (a
/// premature end, corrupt data) makes it an InvalidInputError rather than a grey-filled image.
Image decodeJpeg(Bytes bytes, const std::string& name);
/// Decodes the first part of an OpenEXR file (scanline or tiled, 1-4 channels, half or float).
Image decodeExr(Bytes bytes, const std::string& name);
/// Decodes the first image of a TIFF (8/16-bit or float grey/RGB(A), strips or tiles; other
/// layouts through libtiff's 8-bit RGBA reader).
Image decodeTiff(Bytes bytes, const std::string& name);

/// Checks a PNG's chunks (complete, checksums, IHDR first, image data, IEND): libpng would
/// otherwise accept some damage with only a warning.
void checkPngStructure(Bytes bytes, const std::string& name);

// Header reads: the width and height from the file's header only, no pixel decoded.

/// Size of a PNG file.
Size pngSize(const std::filesystem::path& path);
/// Size of a JPEG file.
Size jpegSize(const std::filesystem::path& path);
/// Size (data window) of an OpenEXR file.
Size exrSize(const std::filesystem::path& path);
/// Size of a TIFF file's first image.
Size tiffSize(const std::filesystem::path& path);

// Encoding of a checked image (1-4 channels, buffer size matching) to `file`; IoError prefixed
// by `where` on failure (the caller removes the partial file).

/// Writes an 8- or 16-bit PNG (zlib level 6).
void writePng(const std::filesystem::path& file, const Image& image, bool sixteenBit,
              const std::string& where);
/// Encodes an 8- or 16-bit PNG into memory.
std::vector<unsigned char> encodePng(const Image& image, bool sixteenBit, const std::string& where);
/// Writes an 8-bit JPEG (grey or RGB, quality 98).
void writeJpeg(const std::filesystem::path& file, const Image& image, const std::string& where);
/// Writes a ZIP-compressed scanline OpenEXR, half or float (channels Y, YA, RGB or RGBA).
void writeExr(const std::filesystem::path& file, const Image& image, bool half,
              const std::string& where);
/// Writes a deflate-compressed TIFF of 8-bit, 16-bit or float samples (alpha unassociated).
void writeTiff(const std::filesystem::path& file, const Image& image, PixelFormat format,
               const std::string& where);

}  // namespace texgrad::codec
