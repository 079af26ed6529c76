// TIFF through libtiff. Each file is opened with its own error and warning handlers (libtiff's
// open options), so nothing is printed and no process-wide handler is changed; the first error
// message is kept for texgrad's.
#include <tiffio.h>

#include <array>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <memory>

#include "image_codecs.h"
#include "texgrad/core/error.h"

namespace texgrad::codec {
namespace {

/// Largest single allocation libtiff may make for one file (a strip, a tile, a tag array):
/// twice the largest 16384² RGBA float strip texgrad writes, far above any sane layout.
constexpr tmsize_t kMaxLibtiffAllocation = tmsize_t{1} << 30;

/// libtiff's first error message for one file.
struct TiffMessage {
  std::array<char, 256> text{};
};

int onTiffError(TIFF*, void* user, const char* module, const char* format, va_list arguments) {
  auto* kept = static_cast<TiffMessage*>(user);
  if (kept->text[0] == '\0') {
    std::array<char, 200> body{};
    std::vsnprintf(body.data(), body.size(), format, arguments);
    std::snprintf(kept->text.data(), kept->text.size(), "%s%s%s", module ? module : "",
                  module ? ": " : "", body.data());
  }
  return 1;  // handled: libtiff's process-wide handler is not called
}

int onTiffWarning(TIFF*, void*, const char*, const char*, va_list) { return 1; }

/// Open options that send this file's messages to `message`.
std::unique_ptr<TIFFOpenOptions, void (*)(TIFFOpenOptions*)> openOptions(TiffMessage* message) {
  std::unique_ptr<TIFFOpenOptions, void (*)(TIFFOpenOptions*)> options(TIFFOpenOptionsAlloc(),
                                                                       TIFFOpenOptionsFree);
  if (!options) throw std::bad_alloc();
  TIFFOpenOptionsSetErrorHandlerExtR(options.get(), onTiffError, message);
  TIFFOpenOptionsSetWarningHandlerExtR(options.get(), onTiffWarning, nullptr);
  TIFFOpenOptionsSetMaxSingleMemAlloc(options.get(), kMaxLibtiffAllocation);
  return options;
}

using TiffHandle = std::unique_ptr<TIFF, void (*)(TIFF*)>;

/// Bytes in memory read by libtiff through its client interface (mapped: no copies).
struct MemoryFile {
  Bytes bytes;
  uint64_t position = 0;
};

MemoryFile& memoryOf(thandle_t handle) { return *static_cast<MemoryFile*>(handle); }

tmsize_t readMemory(thandle_t handle, void* to, tmsize_t size) {
  MemoryFile& file = memoryOf(handle);
  const uint64_t left = file.bytes.size() - std::min<uint64_t>(file.position, file.bytes.size());
  const auto count = static_cast<size_t>(std::min<uint64_t>(left, static_cast<uint64_t>(size)));
  std::memcpy(to, file.bytes.data() + file.position, count);
  file.position += count;
  return static_cast<tmsize_t>(count);
}

tmsize_t writeNothing(thandle_t, void*, tmsize_t) { return 0; }

toff_t seekMemory(thandle_t handle, toff_t offset, int whence) {
  MemoryFile& file = memoryOf(handle);
  const uint64_t base = whence == SEEK_CUR ? file.position
                        : whence == SEEK_END ? file.bytes.size()
                                             : 0;
  file.position = base + offset;
  return file.position;
}

int closeNothing(thandle_t) { return 0; }

toff_t sizeOfMemory(thandle_t handle) { return memoryOf(handle).bytes.size(); }

int mapMemory(thandle_t handle, void** base, toff_t* size) {
  MemoryFile& file = memoryOf(handle);
  *base = const_cast<unsigned char*>(file.bytes.data());  // libtiff only reads a read-only map
  *size = file.bytes.size();
  return 1;
}

void unmapNothing(thandle_t, void*, toff_t) {}

/// What a TIFF directory says about its samples.
struct TiffLayout {
  uint32_t width = 0, height = 0;
  uint16_t samples = 1, bits = 1, sampleFormat = SAMPLEFORMAT_UINT, planar = PLANARCONFIG_CONTIG,
           photometric = PHOTOMETRIC_MINISBLACK, extraSamples = 0,
           orientation = ORIENTATION_TOPLEFT;

  /// 8/16-bit integers or 32-bit floats, grey or RGB, interleaved or in planes: read as stored.
  bool direct() const {
    const bool integer = sampleFormat == SAMPLEFORMAT_UINT && (bits == 8 || bits == 16);
    const bool real = sampleFormat == SAMPLEFORMAT_IEEEFP && bits == 32;
    const bool colour = photometric == PHOTOMETRIC_MINISBLACK ||
                        (photometric == PHOTOMETRIC_RGB && samples >= 3);
    return (integer || real) && colour;
  }
  PixelFormat format() const {
    return bits == 8 ? PixelFormat::UInt8 : bits == 16 ? PixelFormat::UInt16 : PixelFormat::Float;
  }
  /// Channels of the 8-bit RGBA reading of another layout: grey or colour, with alpha if the
  /// file has extra samples (CMYK's fourth sample is ink, not alpha).
  int rgbaChannels() const {
    const bool grey =
        photometric == PHOTOMETRIC_MINISBLACK || photometric == PHOTOMETRIC_MINISWHITE;
    const int alpha = extraSamples > 0 ? 1 : 0;
    return (grey ? 1 : 3) + alpha;
  }
};

TiffLayout layoutOf(TIFF* tiff) {
  TiffLayout layout;
  TIFFGetField(tiff, TIFFTAG_IMAGEWIDTH, &layout.width);
  TIFFGetField(tiff, TIFFTAG_IMAGELENGTH, &layout.height);
  TIFFGetFieldDefaulted(tiff, TIFFTAG_SAMPLESPERPIXEL, &layout.samples);
  TIFFGetFieldDefaulted(tiff, TIFFTAG_BITSPERSAMPLE, &layout.bits);
  TIFFGetFieldDefaulted(tiff, TIFFTAG_SAMPLEFORMAT, &layout.sampleFormat);
  TIFFGetFieldDefaulted(tiff, TIFFTAG_PLANARCONFIG, &layout.planar);
  TIFFGetFieldDefaulted(tiff, TIFFTAG_ORIENTATION, &layout.orientation);
  uint16_t* extraTypes = nullptr;
  TIFFGetFieldDefaulted(tiff, TIFFTAG_EXTRASAMPLES, &layout.extraSamples, &extraTypes);
  if (!TIFFGetField(tiff, TIFFTAG_PHOTOMETRIC, &layout.photometric))
    layout.photometric = layout.samples >= 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK;
  return layout;
}

/// `count` samples of `bits` bits (8, 16: integer levels; 32: float) as floats, into every
/// `stride`-th float from `to`.
void samplesToFloats(const unsigned char* from, size_t count, int bits, float* to,
                     size_t stride) {
  for (size_t k = 0; k < count; ++k) {
    float& value = to[k * stride];
    if (bits == 8) {
      value = levelValue(from[k]);
    } else if (bits == 16) {
      uint16_t level = 0;
      std::memcpy(&level, from + 2 * k, 2);
      value = levelValue(level);
    } else {
      std::memcpy(&value, from + 4 * k, 4);
    }
  }
}

/// Largest tile area accepted beyond the image's own: a tile may overhang the image, but a
/// tiny file declaring huge tiles would otherwise allocate gigabytes.
constexpr uint64_t kMinTileAreaBound = uint64_t{1} << 20;

/// Reads 8/16-bit or float samples, strips or tiles, interleaved or one plane per channel, into
/// `image` in file order (the Orientation tag is not applied, as OpenImageIO did not); false on
/// an error.
bool readDirect(TIFF* tiff, const TiffLayout& layout, Image& image) {
  const int bits = layout.bits;
  const bool planes = layout.planar == PLANARCONFIG_SEPARATE;
  const int reads = planes ? image.channels : 1;            // one pass per plane
  const size_t perTexel = planes ? 1 : image.channels;       // samples per texel in one read
  const size_t stride = planes ? static_cast<size_t>(image.channels) : 1;
  const size_t bytesPerTexel = perTexel * static_cast<size_t>(bits / 8);
  if (!TIFFIsTiled(tiff)) {
    std::vector<unsigned char> row(static_cast<size_t>(TIFFScanlineSize(tiff)));
    for (int s = 0; s < reads; ++s)
      for (uint32_t y = 0; y < layout.height; ++y) {
        if (TIFFReadScanline(tiff, row.data(), y, static_cast<uint16_t>(s)) < 0) return false;
        samplesToFloats(row.data(), layout.width * perTexel, bits,
                        fileRow(image, static_cast<int>(y)) + s, stride);
      }
    return true;
  }
  uint32_t tileWidth = 0, tileHeight = 0;
  TIFFGetField(tiff, TIFFTAG_TILEWIDTH, &tileWidth);
  TIFFGetField(tiff, TIFFTAG_TILELENGTH, &tileHeight);
  std::vector<unsigned char> tile(uint64_t{tileWidth} * tileHeight * bytesPerTexel);
  for (int s = 0; s < reads; ++s)
    for (uint32_t y0 = 0; y0 < layout.height; y0 += tileHeight)
      for (uint32_t x0 = 0; x0 < layout.width; x0 += tileWidth) {
        if (TIFFReadTile(tiff, tile.data(), x0, y0, 0, static_cast<uint16_t>(s)) < 0)
          return false;
        const uint32_t columns = std::min(tileWidth, layout.width - x0);
        for (uint32_t r = 0; r < tileHeight && y0 + r < layout.height; ++r)
          samplesToFloats(tile.data() + r * tileWidth * bytesPerTexel, columns * perTexel, bits,
                          fileRow(image, static_cast<int>(y0 + r)) + x0 * image.channels + s,
                          stride);
      }
  return true;
}

/// Throws InvalidInputError naming `name` unless the tiles of a tiled file have a sane size:
/// not empty, and not far larger than the image (which would allocate gigabytes for a tiny file).
void checkTiles(TIFF* tiff, const TiffLayout& layout, const std::string& name) {
  if (!TIFFIsTiled(tiff)) return;
  uint32_t tileWidth = 0, tileHeight = 0;
  TIFFGetField(tiff, TIFFTAG_TILEWIDTH, &tileWidth);
  TIFFGetField(tiff, TIFFTAG_TILELENGTH, &tileHeight);
  const uint64_t area = uint64_t{tileWidth} * tileHeight;
  if (area == 0 ||
      area > std::max(kMinTileAreaBound, 4 * uint64_t{layout.width} * uint64_t{layout.height}))
    throw InvalidInputError(name + " is corrupt: it declares " + std::to_string(tileWidth) +
                            " x " + std::to_string(tileHeight) + " tiles for a " +
                            std::to_string(layout.width) + " x " +
                            std::to_string(layout.height) + " image");
}

/// Reads any other layout through libtiff's 8-bit RGBA interface, in file order like
/// readDirect; false on an error.
bool readRgba(TIFF* tiff, const TiffLayout& layout, Image& image) {
  std::vector<uint32_t> raster(static_cast<size_t>(image.width) *
                               static_cast<size_t>(image.height));
  // Asked for the file's own orientation, libtiff returns the rows as stored: raster row 0 is
  // the file's first row.
  if (!TIFFReadRGBAImageOriented(tiff, static_cast<uint32_t>(image.width),
                                 static_cast<uint32_t>(image.height), raster.data(),
                                 layout.orientation, 0))
    return false;
  const bool colour = image.channels >= 3, alpha = image.channels % 2 == 0;
  for (int y = 0; y < image.height; ++y) {
    float* texel = fileRow(image, y);
    for (int x = 0; x < image.width; ++x) {
      const uint32_t abgr = raster[static_cast<size_t>(y) * image.width + x];
      *texel++ = levelValue(static_cast<uint8_t>(TIFFGetR(abgr)));
      if (colour) {
        *texel++ = levelValue(static_cast<uint8_t>(TIFFGetG(abgr)));
        *texel++ = levelValue(static_cast<uint8_t>(TIFFGetB(abgr)));
      }
      if (alpha) *texel++ = levelValue(static_cast<uint8_t>(TIFFGetA(abgr)));
    }
  }
  return true;
}

std::string problem(const TiffMessage& message) {
  return oneLine(message.text[0] ? message.text.data() : "libtiff could not read it");
}

/// Opens bytes in memory for reading; InvalidInputError naming `name` if libtiff refuses them.
TiffHandle openMemory(MemoryFile* memory, TiffMessage* message, const std::string& name) {
  const auto options = openOptions(message);
  TIFF* tiff = TIFFClientOpenExt(name.c_str(), "r", memory, readMemory, writeNothing,
                                 seekMemory, closeNothing, sizeOfMemory, mapMemory,
                                 unmapNothing, options.get());
  if (!tiff) throw InvalidInputError(name + " is truncated or corrupt: " + problem(*message));
  return {tiff, TIFFClose};
}

/// Writes the rows of `image` as `format` samples; false on an error.
bool writeRows(TIFF* tiff, const Image& image, PixelFormat format) {
  const size_t samples = static_cast<size_t>(image.width) * static_cast<size_t>(image.channels);
  std::vector<unsigned char> row(samples * (format == PixelFormat::UInt8    ? 1
                                            : format == PixelFormat::UInt16 ? 2
                                                                            : 4));
  for (int y = 0; y < image.height; ++y) {
    if (format == PixelFormat::UInt8)
      quantiseRow(image, y, row.data());
    else if (format == PixelFormat::UInt16)
      quantiseRow(image, y, reinterpret_cast<uint16_t*>(row.data()));
    else
      std::memcpy(row.data(), fileRow(image, y), samples * sizeof(float));
    if (TIFFWriteScanline(tiff, row.data(), static_cast<uint32_t>(y), 0) < 0) return false;
  }
  return TIFFFlush(tiff) == 1;
}

/// Uncompressed size above which a written TIFF is a BigTIFF (classic offsets stop at 4 GB).
constexpr uint64_t kBigTiffBytes = uint64_t{3} << 30;

}  // namespace

Image decodeTiff(Bytes bytes, const std::string& name) {
  MemoryFile memory{bytes};
  TiffMessage message;
  const TiffHandle tiff = openMemory(&memory, &message, name);
  const TiffLayout layout = layoutOf(tiff.get());
  const bool direct = layout.direct();
  const int channels = direct ? layout.samples : layout.rgbaChannels();
  std::array<char, 1024> why{};
  if (!direct && !TIFFRGBAImageOK(tiff.get(), why.data()))
    throw UnsupportedError(name + ": " + oneLine(why.data()) +
                           "; texgrad reads 8/16-bit and float grey or RGB(A) TIFFs and what "
                           "libtiff turns into 8-bit RGBA (convert it, e.g. oiiotool IN -o OUT.tif)");
  if (layout.width > INT32_MAX || layout.height > INT32_MAX || layout.width == 0 ||
      layout.height == 0)
    throw InvalidInputError(name + " declares an impossible size (" +
                            std::to_string(layout.width) + " x " +
                            std::to_string(layout.height) + ")");
  checkDeclaredImage(static_cast<int>(layout.width), static_cast<int>(layout.height), channels,
                     name);
  checkTiles(tiff.get(), layout, name);
  Image image(static_cast<int>(layout.width), static_cast<int>(layout.height), channels,
              direct ? layout.format() : PixelFormat::UInt8);
  if (!(direct ? readDirect(tiff.get(), layout, image) : readRgba(tiff.get(), layout, image)) ||
      message.text[0] != '\0')
    throw InvalidInputError(name + " is truncated or corrupt: " + problem(message));
  return image;
}

Size tiffSize(const std::filesystem::path& path) {
  TiffMessage message;
  const auto options = openOptions(&message);
  const TiffHandle tiff(TIFFOpenExt(path.c_str(), "r", options.get()), TIFFClose);
  if (!tiff)
    throw InvalidInputError("cannot read the header of " + path.string() + ": " +
                            problem(message));
  const TiffLayout layout = layoutOf(tiff.get());
  if (layout.width == 0 || layout.height == 0 || layout.width > INT32_MAX ||
      layout.height > INT32_MAX)
    throw InvalidInputError(path.string() + " declares an impossible size");
  return {static_cast<int>(layout.width), static_cast<int>(layout.height)};
}

void writeTiff(const std::filesystem::path& file, const Image& image, PixelFormat format,
               const std::string& where) {
  const uint16_t bits =
      format == PixelFormat::UInt8 ? 8 : format == PixelFormat::UInt16 ? 16 : 32;
  const uint64_t raw = static_cast<uint64_t>(image.pixels.size()) * (bits / 8);
  TiffMessage message;
  const auto options = openOptions(&message);
  const TiffHandle tiff(TIFFOpenExt(file.c_str(), raw > kBigTiffBytes ? "w8" : "w", options.get()),
                        TIFFClose);
  if (!tiff) throw IoError(where + problem(message));
  TIFF* t = tiff.get();
  const bool colour = image.channels >= 3, alpha = image.channels % 2 == 0;
  TIFFSetField(t, TIFFTAG_IMAGEWIDTH, static_cast<uint32_t>(image.width));
  TIFFSetField(t, TIFFTAG_IMAGELENGTH, static_cast<uint32_t>(image.height));
  TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, static_cast<uint16_t>(image.channels));
  TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, bits);
  TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, bits == 32 ? SAMPLEFORMAT_IEEEFP : SAMPLEFORMAT_UINT);
  TIFFSetField(t, TIFFTAG_PHOTOMETRIC, colour ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK);
  TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(t, TIFFTAG_ORIENTATION, ORIENTATION_TOPLEFT);
  TIFFSetField(t, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
  // Differences between neighbours compress better than the samples (a third smaller here).
  TIFFSetField(t, TIFFTAG_PREDICTOR, bits == 32 ? PREDICTOR_FLOATINGPOINT : PREDICTOR_HORIZONTAL);
  if (alpha) {
    const uint16_t extra[1] = {EXTRASAMPLE_UNASSALPHA};
    TIFFSetField(t, TIFFTAG_EXTRASAMPLES, uint16_t{1}, extra);
  }
  TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, TIFFDefaultStripSize(t, 0));
  if (!writeRows(t, image, format) || message.text[0] != '\0')
    throw IoError(where + problem(message));
}

}  // namespace texgrad::codec
