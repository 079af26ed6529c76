// The image codecs on layouts texgrad never writes but reads: files made by the format libraries
// themselves (interlaced and palette PNGs, tiled and planar TIFFs, OpenEXR channel orders, CMYK
// JPEGs and TIFFs), header sizes, content no codec takes, headers that declare far more than the
// file holds (refused before any large allocation), and writes that fail.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <gtest/gtest.h>
#include <png.h>
#include <tiffio.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>

// jpeglib.h needs FILE and size_t declared first.
#include <jpeglib.h>

#include "io/image_codecs.h"
#include "test_paths.h"
#include "texgrad/core/error.h"
#include "texgrad/io/image_io.h"

namespace texgrad {
namespace {

using test::tempDir;

/// Level of texel (x, y) of file row order (top first), channel c: distinct everywhere.
unsigned levelAt(int x, int y, int c) { return static_cast<unsigned>(x * 7 + y * 13 + c * 61) % 256; }

/// The value readImage gives level `level` of an 8-bit file.
float valueOf(unsigned level) { return static_cast<float>(level) * (1.0f / 255.0f); }

/// Expects `image` to hold levelAt in every channel, with file row y as texel row height-1-y.
void expectLevels(const Image& image, int width, int height, int channels) {
  ASSERT_EQ(image.width, width);
  ASSERT_EQ(image.height, height);
  ASSERT_EQ(image.channels, channels);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < channels; ++c)
        ASSERT_EQ(image.at(x, height - 1 - y, c), valueOf(levelAt(x, y, c)))
            << "file texel " << x << ", " << y << ", channel " << c;
}

/// Expects `read` to throw E whose message holds `part`.
template <typename E>
void expectRefusal(const std::function<void()>& read, const std::string& part) {
  try {
    read();
    ADD_FAILURE() << "expected a refusal mentioning '" << part << "'";
  } catch (const E& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

/// libpng writing `path`, for files texgrad never writes itself: the test sets the header and
/// writes the rows; the destructor ends the file.
struct LibpngFile {
  std::FILE* file;
  png_structp png;
  png_infop info;

  explicit LibpngFile(const std::filesystem::path& path)
      : file(std::fopen(path.c_str(), "wb")),
        png(png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr)),
        info(png_create_info_struct(png)) {
    png_init_io(png, file);
  }
  ~LibpngFile() {
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
  }
  LibpngFile(const LibpngFile&) = delete;
  LibpngFile& operator=(const LibpngFile&) = delete;
};

/// Writes an 8-bit PNG of levelAt with libpng: RGB, Adam7-interlaced when asked.
void writePngWithLibpng(const std::filesystem::path& path, int width, int height,
                        bool interlaced) {
  LibpngFile out(path);
  png_set_IHDR(out.png, out.info, width, height, 8, PNG_COLOR_TYPE_RGB,
               interlaced ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(out.png, out.info);
  std::vector<unsigned char> pixels(size_t(width) * height * 3);
  std::vector<png_bytep> rows(static_cast<size_t>(height));
  for (int y = 0; y < height; ++y) {
    rows[size_t(y)] = pixels.data() + size_t(y) * width * 3;
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) rows[size_t(y)][x * 3 + c] = static_cast<png_byte>(levelAt(x, y, c));
  }
  png_write_image(out.png, rows.data());
}

TEST(ImageCodecs, InterlacedPngDecodesLikeItsPixels) {
  const auto dir = tempDir("codec_interlaced");
  writePngWithLibpng(dir / "plain.png", 19, 11, false);
  writePngWithLibpng(dir / "adam7.png", 19, 11, true);
  expectLevels(readImage(dir / "plain.png"), 19, 11, 3);
  expectLevels(readImage(dir / "adam7.png"), 19, 11, 3);
}

TEST(ImageCodecs, PaletteWithTransparencyBecomesRgba) {
  const auto dir = tempDir("codec_palette");
  const auto path = dir / "palette.png";
  const int width = 4, height = 2;
  std::array<png_color, 8> palette{};
  std::array<png_byte, 8> alpha{};
  for (int k = 0; k < 8; ++k) {
    palette[size_t(k)] = {static_cast<png_byte>(30 * k), static_cast<png_byte>(255 - 30 * k),
                          static_cast<png_byte>(k)};
    alpha[size_t(k)] = static_cast<png_byte>(k % 2 == 0 ? 255 : 40);
  }
  {
    LibpngFile out(path);
    png_set_IHDR(out.png, out.info, width, height, 8, PNG_COLOR_TYPE_PALETTE, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_PLTE(out.png, out.info, palette.data(), 8);
    png_set_tRNS(out.png, out.info, alpha.data(), 8, nullptr);
    png_write_info(out.png, out.info);
    for (int y = 0; y < height; ++y) {
      std::array<png_byte, width> row{};
      for (int x = 0; x < width; ++x) row[size_t(x)] = static_cast<png_byte>(y * width + x);
      png_write_row(out.png, row.data());
    }
  }

  const Image image = readImage(path);
  ASSERT_EQ(image.channels, 4);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t k = size_t(y * width + x);
      EXPECT_EQ(image.at(x, height - 1 - y, 0), valueOf(palette[k].red));
      EXPECT_EQ(image.at(x, height - 1 - y, 1), valueOf(palette[k].green));
      EXPECT_EQ(image.at(x, height - 1 - y, 3), valueOf(alpha[k])) << "alpha from tRNS";
    }
}

TEST(ImageCodecs, RgbWithATransparentColourGetsAlpha) {
  const auto dir = tempDir("codec_colour_key");
  const auto path = dir / "key.png";
  {
    LibpngFile out(path);
    png_set_IHDR(out.png, out.info, 2, 1, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_color_16 key{};
    key.red = 10;
    key.green = 20;
    key.blue = 30;
    png_set_tRNS(out.png, out.info, nullptr, 0, &key);  // exactly this colour is transparent
    png_write_info(out.png, out.info);
    std::array<png_byte, 6> row = {10, 20, 30, 10, 20, 31};
    png_write_row(out.png, row.data());
  }

  const Image image = readImage(path);
  ASSERT_EQ(image.channels, 4);
  EXPECT_EQ(image.at(0, 0, 3), 0.0f) << "the key colour";
  EXPECT_EQ(image.at(1, 0, 3), 1.0f) << "any other colour";
  EXPECT_EQ(image.at(1, 0, 2), valueOf(31));
}

/// Writes levelAt as an 8-bit RGB TIFF with libtiff: strips, 16 x 16 tiles, or separate planes.
enum class TiffLayout { Strips, Tiles, Planes };

void writeTiffWithLibtiff(const std::filesystem::path& path, int width, int height,
                          TiffLayout layout) {
  TIFF* tiff = TIFFOpen(path.c_str(), "w");
  ASSERT_NE(tiff, nullptr);
  TIFFSetField(tiff, TIFFTAG_IMAGEWIDTH, uint32_t(width));
  TIFFSetField(tiff, TIFFTAG_IMAGELENGTH, uint32_t(height));
  TIFFSetField(tiff, TIFFTAG_SAMPLESPERPIXEL, uint16_t{3});
  TIFFSetField(tiff, TIFFTAG_BITSPERSAMPLE, uint16_t{8});
  TIFFSetField(tiff, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_RGB);
  TIFFSetField(tiff, TIFFTAG_PLANARCONFIG,
               layout == TiffLayout::Planes ? PLANARCONFIG_SEPARATE : PLANARCONFIG_CONTIG);
  TIFFSetField(tiff, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
  if (layout == TiffLayout::Tiles) {
    const uint32_t tile = 16;
    TIFFSetField(tiff, TIFFTAG_TILEWIDTH, tile);
    TIFFSetField(tiff, TIFFTAG_TILELENGTH, tile);
    std::vector<unsigned char> buffer(tile * tile * 3);
    for (uint32_t y0 = 0; y0 < uint32_t(height); y0 += tile)
      for (uint32_t x0 = 0; x0 < uint32_t(width); x0 += tile) {
        for (uint32_t r = 0; r < tile; ++r)
          for (uint32_t x = 0; x < tile; ++x)
            for (int c = 0; c < 3; ++c)
              buffer[(r * tile + x) * 3 + c] =
                  static_cast<unsigned char>(levelAt(int(x0 + x), int(y0 + r), c));
        ASSERT_GE(TIFFWriteTile(tiff, buffer.data(), x0, y0, 0, 0), 0);
      }
  } else {
    const int planes = layout == TiffLayout::Planes ? 3 : 1;
    const int perRow = layout == TiffLayout::Planes ? 1 : 3;
    std::vector<unsigned char> row(size_t(width) * perRow);
    for (int s = 0; s < planes; ++s)
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x)
          for (int c = 0; c < perRow; ++c)
            row[size_t(x * perRow + c)] = static_cast<unsigned char>(levelAt(x, y, s + c));
        ASSERT_GE(TIFFWriteScanline(tiff, row.data(), uint32_t(y), uint16_t(s)), 0);
      }
  }
  TIFFClose(tiff);
}

TEST(ImageCodecs, StripTiledAndPlanarTiffsDecodeAlike) {
  const auto dir = tempDir("codec_tiff");
  // 37 x 23: partial tiles at the right and top edges.
  for (const auto& [name, layout] : {std::pair{"strips.tif", TiffLayout::Strips},
                                     std::pair{"tiles.tif", TiffLayout::Tiles},
                                     std::pair{"planes.tif", TiffLayout::Planes}}) {
    SCOPED_TRACE(name);
    writeTiffWithLibtiff(dir / name, 37, 23, layout);
    expectLevels(readImage(dir / name), 37, 23, 3);
    EXPECT_EQ(readImageSize(dir / name), (std::pair<int, int>{37, 23}));
  }
}

/// Writes a 3 x 2 OpenEXR with OpenEXR: channel `names[k]` holds the constant `k + 1`.
void writeExrWithOpenExr(const std::filesystem::path& path, const std::vector<std::string>& names) {
  const int width = 3, height = 2;
  Imf::Header header(width, height);
  Imf::FrameBuffer buffer;
  std::vector<std::vector<float>> planes;
  for (size_t k = 0; k < names.size(); ++k)
    planes.emplace_back(size_t(width * height), static_cast<float>(k + 1));
  for (size_t k = 0; k < names.size(); ++k) {
    header.channels().insert(names[k], Imf::Channel(Imf::FLOAT));
    buffer.insert(names[k], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes[k].data()),
                                       sizeof(float), width * sizeof(float)));
  }
  Imf::OutputFile out(path.c_str(), header);
  out.setFrameBuffer(buffer);
  out.writePixels(height);
}

TEST(ImageCodecs, ExrChannelsComeAsRgbOrGreyWithAlphaLast) {
  const auto dir = tempDir("codec_exr_channels");
  // OpenEXR stores channels by name (A, B, G, R); texgrad holds R, G, B, then A.
  writeExrWithOpenExr(dir / "rgba.exr", {"R", "G", "B", "A"});
  const Image rgba = readImage(dir / "rgba.exr");
  ASSERT_EQ(rgba.channels, 4);
  EXPECT_EQ(rgba.format, PixelFormat::Float);
  for (int c = 0; c < 4; ++c) EXPECT_EQ(rgba.at(1, 1, c), static_cast<float>(c + 1)) << c;
  writeExrWithOpenExr(dir / "ya.exr", {"Y", "A"});
  const Image ya = readImage(dir / "ya.exr");
  ASSERT_EQ(ya.channels, 2);
  EXPECT_EQ(ya.at(0, 0, 0), 1.0f) << "Y first";
  EXPECT_EQ(ya.at(0, 0, 1), 2.0f) << "alpha last";
  EXPECT_EQ(readImageSize(dir / "ya.exr"), (std::pair<int, int>{3, 2}));
}

TEST(ImageCodecs, HeaderSizeIsTheDecodedSizeInEveryFormat) {
  const auto dir = tempDir("codec_sizes");
  Image image(37, 23, 3, PixelFormat::UInt8);
  for (const char* name : {"s.png", "s.jpg", "s.exr", "s.tif"}) {
    writeImage(dir / name, image);
    EXPECT_EQ(readImageSize(dir / name), (std::pair<int, int>{37, 23})) << name;
    EXPECT_EQ(readImage(dir / name).width, 37) << name;
  }
}

/// Writes a black 8 x 8 JPEG with libjpeg, in `space` (JCS_RGB or JCS_CMYK), progressive if asked.
void writeJpegWithLibjpeg(const std::filesystem::path& path, J_COLOR_SPACE space,
                          bool progressive) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  ASSERT_NE(file, nullptr);
  jpeg_compress_struct info{};
  jpeg_error_mgr errors{};
  info.err = jpeg_std_error(&errors);
  jpeg_create_compress(&info);
  jpeg_stdio_dest(&info, file);
  info.image_width = 8;
  info.image_height = 8;
  info.input_components = space == JCS_CMYK ? 4 : 3;
  info.in_color_space = space;
  jpeg_set_defaults(&info);
  if (progressive) jpeg_simple_progression(&info);
  jpeg_start_compress(&info, TRUE);
  std::array<JSAMPLE, 8 * 4> row{};
  for (int y = 0; y < 8; ++y) {
    JSAMPROW rows[1] = {row.data()};
    jpeg_write_scanlines(&info, rows, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  std::fclose(file);
}

TEST(ImageCodecs, CmykJpegIsUnsupportedWithAWayOut) {
  const auto dir = tempDir("codec_cmyk");
  const auto path = dir / "cmyk.jpg";
  writeJpegWithLibjpeg(path, JCS_CMYK, false);
  expectRefusal<UnsupportedError>([&] { readImage(path); }, "CMYK");
}

TEST(ImageCodecs, OtherFormatsAreUnsupportedAndNamed) {
  const auto dir = tempDir("codec_other");
  std::ofstream(dir / "image.bmp", std::ios::binary) << "BM" << std::string(60, '\0');
  const auto path = dir / "image.bmp";
  for (const char* part : {"image.bmp", "a BMP image", "PNG, JPEG, OpenEXR and TIFF"}) {
    expectRefusal<UnsupportedError>([&] { readImage(path); }, part);
    expectRefusal<UnsupportedError>([&] { readImageSize(path); }, part);
  }
}

std::string readBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

/// Writes an 8 x 8 RGB JPEG to `path` (progressive if asked), then `edit(bytes, at)` on its bytes
/// with `at` the offset of its frame header's marker (SOF2 or SOF0: marker, length, precision,
/// height, width), and writes those back.
template <typename Edit>
void writeJpegWithEditedFrameHeader(const std::filesystem::path& path, bool progressive,
                                    Edit edit) {
  writeJpegWithLibjpeg(path, JCS_RGB, progressive);
  std::string bytes = readBytes(path);
  const size_t sof = bytes.find(progressive ? "\xff\xc2" : "\xff\xc0");
  ASSERT_NE(sof, std::string::npos);
  edit(bytes, sof);
  writeBytes(path, bytes);
}

TEST(ImageCodecs, ProgressiveJpegDeclaringAHugeImageIsRefusedBeforeDecoding) {
  const auto path = tempDir("codec_jpeg_huge") / "huge.jpg";
  writeJpegWithEditedFrameHeader(path, true, [](std::string& bytes, size_t sof) {
    for (size_t at : {sof + 5, sof + 7}) {  // 40000 x 40000: 1.6 billion texels
      bytes[at] = static_cast<char>(0x9c);
      bytes[at + 1] = static_cast<char>(0x40);
    }
  });
  expectRefusal<UnsupportedError>([&] { readImage(path); }, "40000 x 40000");
}

TEST(ImageCodecs, TwelveBitJpegIsUnsupportedWithAWayOut) {
  const auto path = tempDir("codec_jpeg_12bit") / "twelve.jpg";
  writeJpegWithEditedFrameHeader(path, false,
                                 [](std::string& bytes, size_t sof) { bytes[sof + 4] = 12; });
  expectRefusal<UnsupportedError>([&] { readImage(path); }, "12-bit JPEG");
  expectRefusal<UnsupportedError>([&] { readImageSize(path); }, "12-bit JPEG");
}

TEST(ImageCodecs, TiffDeclaringHugeTilesIsRefused) {
  const auto dir = tempDir("codec_tiff_tiles");
  const auto path = dir / "tiles.tif";
  writeTiffWithLibtiff(path, 16, 16, TiffLayout::Tiles);
  std::string bytes = readBytes(path);
  ASSERT_EQ(bytes.substr(0, 2), "II");
  uint32_t ifd = 0;
  std::memcpy(&ifd, bytes.data() + 4, 4);
  uint16_t entries = 0;
  std::memcpy(&entries, bytes.data() + ifd, 2);
  int patched = 0;
  for (uint16_t e = 0; e < entries; ++e) {  // 12-byte entries: tag, type, count, value
    char* entry = bytes.data() + ifd + 2 + 12 * e;
    uint16_t tag = 0;
    std::memcpy(&tag, entry, 2);
    if (tag != TIFFTAG_TILEWIDTH && tag != TIFFTAG_TILELENGTH) continue;
    const uint16_t tile = 4096;  // a multiple of 16, as TIFF requires; as SHORT or LONG
    std::memset(entry + 8, 0, 4);
    std::memcpy(entry + 8, &tile, 2);
    ++patched;
  }
  ASSERT_EQ(patched, 2);
  writeBytes(path, bytes);
  expectRefusal<InvalidInputError>([&] { readImage(path); },
                                   "4096 x 4096 tiles for a 16 x 16 image");
}

TEST(ImageCodecs, ExrAttributeLongerThanTheFileIsRefused) {
  const auto dir = tempDir("codec_exr_attribute");
  const auto path = dir / "comment.exr";
  {
    Imf::Header header(2, 2);
    header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
    header.insert("comments", Imf::StringAttribute("a texture"));
    std::array<float, 4> pixels{};
    Imf::FrameBuffer buffer;
    buffer.insert("Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(pixels.data()),
                                  sizeof(float), 2 * sizeof(float)));
    Imf::OutputFile out(path.c_str(), header);
    out.setFrameBuffer(buffer);
    out.writePixels(2);
  }
  std::string bytes = readBytes(path);
  const std::string attribute("comments\0string\0", 16);
  const size_t at = bytes.find(attribute);
  ASSERT_NE(at, std::string::npos);
  const int32_t huge = 0x7fffffff;  // OpenEXR would allocate and fill 2 GB for it
  std::memcpy(bytes.data() + at + attribute.size(), &huge, 4);
  writeBytes(path, bytes);
  expectRefusal<InvalidInputError>([&] { readImage(path); }, "runs past the end");
  expectRefusal<InvalidInputError>([&] { readImageSize(path); }, "runs past the end");
}

TEST(ImageCodecs, CmykTiffIsColourWithoutAlphaInFileRowOrder) {
  const auto dir = tempDir("codec_tiff_cmyk");
  // Top row fully cyan (no red), bottom row no ink (white); the Orientation tag says the rows
  // start at the bottom, which texgrad does not apply (nor did OpenImageIO), on any layout.
  const auto path = dir / "cmyk.tif";
  TIFF* tiff = TIFFOpen(path.c_str(), "w");
  ASSERT_NE(tiff, nullptr);
  TIFFSetField(tiff, TIFFTAG_IMAGEWIDTH, uint32_t{2});
  TIFFSetField(tiff, TIFFTAG_IMAGELENGTH, uint32_t{2});
  TIFFSetField(tiff, TIFFTAG_SAMPLESPERPIXEL, uint16_t{4});
  TIFFSetField(tiff, TIFFTAG_BITSPERSAMPLE, uint16_t{8});
  TIFFSetField(tiff, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_SEPARATED);
  TIFFSetField(tiff, TIFFTAG_INKSET, INKSET_CMYK);
  TIFFSetField(tiff, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(tiff, TIFFTAG_ORIENTATION, ORIENTATION_BOTLEFT);
  std::array<unsigned char, 8> cyan = {255, 0, 0, 0, 255, 0, 0, 0}, white{};
  ASSERT_GE(TIFFWriteScanline(tiff, cyan.data(), 0, 0), 0);
  ASSERT_GE(TIFFWriteScanline(tiff, white.data(), 1, 0), 0);
  TIFFClose(tiff);
  const Image image = readImage(path);
  ASSERT_EQ(image.channels, 3) << "CMYK's fourth sample is ink, not alpha";
  EXPECT_EQ(image.at(0, 1, 0), 0.0f) << "the file's first row is the top texel row";
  EXPECT_EQ(image.at(0, 1, 1), 1.0f);
  EXPECT_EQ(image.at(0, 0, 0), 1.0f);
}

TEST(ImageCodecs, AFailedWriteIsAnErrorInEveryFormat) {
  // /dev/full takes the file's creation but fails every write, like a full disk.
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const Image image(64, 64, 3, PixelFormat::UInt8);
  const std::string where = "w: ";
  EXPECT_THROW(codec::writePng("/dev/full", image, false, where), IoError);
  EXPECT_THROW(codec::writeJpeg("/dev/full", image, where), IoError);
  EXPECT_THROW(codec::writeExr("/dev/full", image, true, where), IoError);
  EXPECT_THROW(codec::writeTiff("/dev/full", image, PixelFormat::UInt8, where), IoError);
}

}  // namespace
}  // namespace texgrad
