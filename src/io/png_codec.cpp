// PNG through libpng. libpng reports an error by longjmp to the last setjmp: each function that
// calls into it sets its own jump point and holds no object with a destructor (buffers and the
// image belong to its caller), so no destructor is ever skipped.
#include <png.h>

#include <array>
#include <bit>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "image_codecs.h"
#include "texgrad/core/error.h"

namespace texgrad::codec {
namespace {

/// libpng's first error message, kept for ours (a fixed buffer: nothing to destroy on longjmp).
struct PngMessage {
  std::array<char, 256> text{};
};

[[noreturn]] void onPngError(png_structp png, png_const_charp message) {
  auto* kept = static_cast<PngMessage*>(png_get_error_ptr(png));
  if (kept->text[0] == '\0') std::snprintf(kept->text.data(), kept->text.size(), "%s", message);
  png_longjmp(png, 1);
}

/// Warnings are dropped: the chunk structure was checked before (checkPngStructure) and a
/// library prints nothing.
void onPngWarning(png_structp, png_const_charp) {}

/// Bytes in memory handed to libpng as its input.
struct MemoryInput {
  Bytes bytes;
  size_t position = 0;
};

void readFromMemory(png_structp png, png_bytep out, size_t length) {
  auto* input = static_cast<MemoryInput*>(png_get_io_ptr(png));
  if (length > input->bytes.size() - input->position) png_error(png, "unexpected end of data");
  std::memcpy(out, input->bytes.data() + input->position, length);
  input->position += length;
}

/// libpng's read structures for the lifetime of one decode.
struct PngReader {
  png_structp png = nullptr;
  png_infop info = nullptr;
  PngMessage message;
  MemoryInput input;

  explicit PngReader(Bytes bytes) : input{bytes} {
    png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &message, onPngError, onPngWarning);
    if (png) info = png_create_info_struct(png);
    if (!png || !info) throw std::bad_alloc();
    png_set_read_fn(png, &input, readFromMemory);
  }
  ~PngReader() { png_destroy_read_struct(&png, &info, nullptr); }
  PngReader(const PngReader&) = delete;
  PngReader& operator=(const PngReader&) = delete;
};

/// What the rows will hold once libpng's transformations are set.
struct RowLayout {
  int width = 0, height = 0, channels = 0, bitDepth = 0, passes = 1;
  size_t rowBytes = 0;
};

/// Reads the header and asks for grey, grey + alpha, RGB or RGBA rows of 8 or 16 bits in native
/// byte order; false on a libpng error.
bool readHeader(png_structp png, png_infop info, RowLayout* layout) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_info(png, info);
  const int colour = png_get_color_type(png, info), depth = png_get_bit_depth(png, info);
  if (colour == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (colour == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  if (depth == 16 && std::endian::native == std::endian::little) png_set_swap(png);
  layout->passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  layout->width = static_cast<int>(png_get_image_width(png, info));
  layout->height = static_cast<int>(png_get_image_height(png, info));
  layout->channels = png_get_channels(png, info);
  layout->bitDepth = png_get_bit_depth(png, info);
  layout->rowBytes = png_get_rowbytes(png, info);
  return true;
}

/// File row `y`, as libpng delivered it, into `image`.
void storeRow(const unsigned char* row, int bitDepth, Image& image, int y) {
  if (bitDepth == 16)
    levelsToRow(reinterpret_cast<const uint16_t*>(row), image, y);
  else
    levelsToRow(row, image, y);
}

/// Decodes the rows into `image` through `buffer` (one row, or every row when the file is
/// interlaced and each pass revisits them); false on a libpng error.
bool readRows(png_structp png, const RowLayout& layout, unsigned char* buffer, Image* image) {
  if (setjmp(png_jmpbuf(png))) return false;
  const bool wholeImage = layout.passes > 1;
  for (int pass = 0; pass < layout.passes; ++pass)
    for (int y = 0; y < layout.height; ++y) {
      unsigned char* row = wholeImage ? buffer + static_cast<size_t>(y) * layout.rowBytes : buffer;
      png_read_row(png, row, nullptr);
      if (!wholeImage) storeRow(row, layout.bitDepth, *image, y);
    }
  if (wholeImage)
    for (int y = 0; y < layout.height; ++y)
      storeRow(buffer + static_cast<size_t>(y) * layout.rowBytes, layout.bitDepth, *image, y);
  png_read_end(png, nullptr);
  return true;
}

std::string corrupt(const std::string& name, const PngMessage& message) {
  return name + " is truncated or corrupt: " + oneLine(message.text.data());
}

/// Where encoded bytes go: an open file or a growing vector.
struct PngSink {
  std::FILE* file = nullptr;
  std::vector<unsigned char>* bytes = nullptr;
};

void writeToSink(png_structp png, png_bytep data, size_t length) {
  auto* sink = static_cast<PngSink*>(png_get_io_ptr(png));
  bool written = true;
  if (sink->file) {
    written = std::fwrite(data, 1, length, sink->file) == length;
  } else {
    try {
      sink->bytes->insert(sink->bytes->end(), data, data + length);
    } catch (const std::bad_alloc&) {
      written = false;
    }
  }
  if (!written) png_error(png, "write failed (disk full or out of memory)");
}

void flushSink(png_structp png) {
  auto* sink = static_cast<PngSink*>(png_get_io_ptr(png));
  if (sink->file && std::fflush(sink->file) != 0) png_error(png, "write failed (disk full?)");
}

/// libpng's write structures for the lifetime of one encode.
struct PngWriter {
  png_structp png = nullptr;
  png_infop info = nullptr;
  PngMessage message;

  explicit PngWriter(PngSink* sink) {
    png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &message, onPngError, onPngWarning);
    if (png) info = png_create_info_struct(png);
    if (!png || !info) throw std::bad_alloc();
    png_set_write_fn(png, sink, writeToSink, flushSink);
  }
  ~PngWriter() { png_destroy_write_struct(&png, &info); }
  PngWriter(const PngWriter&) = delete;
  PngWriter& operator=(const PngWriter&) = delete;
};

/// zlib level of written PNGs (zlib's default: size and speed balanced).
constexpr int kCompressionLevel = 6;

int colourType(int channels) {
  static constexpr std::array<int, 4> types = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA,
                                               PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGB_ALPHA};
  return types[static_cast<size_t>(channels - 1)];
}

/// Writes the header and the rows of `image` through `row` (one row of levels); false on a
/// libpng error.
bool writeRows(png_structp png, png_infop info, const Image& image, bool sixteenBit,
               unsigned char* row) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width),
               static_cast<png_uint_32>(image.height), sixteenBit ? 16 : 8,
               colourType(image.channels), PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, kCompressionLevel);
  png_write_info(png, info);
  if (sixteenBit && std::endian::native == std::endian::little) png_set_swap(png);
  for (int y = 0; y < image.height; ++y) {
    if (sixteenBit)
      quantiseRow(image, y, reinterpret_cast<uint16_t*>(row));
    else
      quantiseRow(image, y, row);
    png_write_row(png, row);
  }
  png_write_end(png, nullptr);
  return true;
}

/// Encodes `image` into `sink`; IoError prefixed by `where` on a libpng error.
void encodeTo(PngSink* sink, const Image& image, bool sixteenBit, const std::string& where) {
  PngWriter writer(sink);
  std::vector<unsigned char> row(static_cast<size_t>(image.width) *
                                 static_cast<size_t>(image.channels) * (sixteenBit ? 2 : 1));
  if (!writeRows(writer.png, writer.info, image, sixteenBit, row.data()))
    throw IoError(where + oneLine(writer.message.text.data()));
}

uint32_t bigEndian32(const unsigned char* p) {
  return uint32_t{p[0]} << 24 | uint32_t{p[1]} << 16 | uint32_t{p[2]} << 8 | uint32_t{p[3]};
}

/// CRC-32 of the PNG specification (ISO 3309 polynomial), over chunk type and data.
uint32_t pngCrc(Bytes bytes) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t n = 0; n < 256; ++n) {
      uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[n] = c;
    }
    return t;
  }();
  uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char b : bytes) crc = table[(crc ^ b) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

/// PNG signature and IHDR: 8 + 4 (length) + 4 (type) + 13 (data) bytes.
constexpr size_t kSignature = 8, kChunkOverhead = 12, kIhdrLength = 13;

}  // namespace

void checkPngStructure(Bytes bytes, const std::string& name) {
  size_t pos = kSignature;
  bool sawIhdr = false, sawIdat = false;
  while (true) {
    if (pos + kChunkOverhead > bytes.size())
      throw InvalidInputError(name + " is truncated (the PNG ends before its IEND chunk)");
    const size_t length = bigEndian32(&bytes[pos]);
    const std::string type(reinterpret_cast<const char*>(&bytes[pos + 4]), 4);
    if (length > bytes.size() - pos - kChunkOverhead)
      throw InvalidInputError(name + " is truncated (PNG chunk " + type + " at byte " +
                              std::to_string(pos) + " runs past the end of the file)");
    const unsigned char* data = &bytes[pos + 8];
    if (pngCrc(bytes.subspan(pos + 4, length + 4)) != bigEndian32(data + length))
      throw InvalidInputError(name + " is corrupt (bad checksum in PNG chunk " + type +
                              " at byte " + std::to_string(pos) + ")");
    if (!sawIhdr) {
      if (type != "IHDR" || length != kIhdrLength)
        throw InvalidInputError(name + " is corrupt (a PNG must start with an IHDR chunk)");
      const uint32_t width = bigEndian32(data), height = bigEndian32(data + 4);
      if (width == 0 || height == 0)
        throw InvalidInputError(name + " declares an empty image (" + std::to_string(width) +
                                " x " + std::to_string(height) + "); re-export the texture");
      sawIhdr = true;
    }
    sawIdat = sawIdat || type == "IDAT";
    if (type == "IEND") break;
    pos += kChunkOverhead + length;
  }
  if (!sawIdat) throw InvalidInputError(name + " is corrupt (the PNG holds no image data)");
}

Image decodePng(Bytes bytes, const std::string& name) {
  checkPngStructure(bytes, name);
  PngReader reader(bytes);
  RowLayout layout;
  if (!readHeader(reader.png, reader.info, &layout))
    throw InvalidInputError(corrupt(name, reader.message));
  checkDeclaredImage(layout.width, layout.height, layout.channels, name);
  Image image(layout.width, layout.height, layout.channels,
              layout.bitDepth == 16 ? PixelFormat::UInt16 : PixelFormat::UInt8);
  const size_t bufferRows = layout.passes > 1 ? static_cast<size_t>(layout.height) : 1;
  std::vector<unsigned char> buffer(bufferRows * layout.rowBytes);
  if (!readRows(reader.png, layout, buffer.data(), &image))
    throw InvalidInputError(corrupt(name, reader.message));
  return image;
}

Size pngSize(const std::filesystem::path& path) {
  // The signature and the IHDR chunk, which a PNG starts with, hold the size.
  std::array<unsigned char, kSignature + kChunkOverhead + kIhdrLength> head{};
  std::ifstream in(path, std::ios::binary);
  in.read(reinterpret_cast<char*>(head.data()), static_cast<std::streamsize>(head.size()));
  const bool png = in.gcount() == static_cast<std::streamsize>(head.size()) &&
                   std::memcmp(head.data(), "\x89PNG\r\n\x1a\n", kSignature) == 0 &&
                   std::memcmp(head.data() + 12, "IHDR", 4) == 0;
  if (!png) throw InvalidInputError(path.string() + " is not a PNG file (no IHDR header)");
  const uint32_t width = bigEndian32(&head[16]), height = bigEndian32(&head[20]);
  if (width == 0 || height == 0 || width > INT32_MAX || height > INT32_MAX)
    throw InvalidInputError(path.string() + " declares an impossible size (" +
                            std::to_string(width) + " x " + std::to_string(height) + ")");
  return {static_cast<int>(width), static_cast<int>(height)};
}

void writePng(const std::filesystem::path& file, const Image& image, bool sixteenBit,
              const std::string& where) {
  OutputFile out(file, where);
  PngSink sink{out.get(), nullptr};
  encodeTo(&sink, image, sixteenBit, where);
  out.close();
}

std::vector<unsigned char> encodePng(const Image& image, bool sixteenBit,
                                     const std::string& where) {
  std::vector<unsigned char> bytes;
  PngSink sink{nullptr, &bytes};
  encodeTo(&sink, image, sixteenBit, where);
  return bytes;
}

}  // namespace texgrad::codec
