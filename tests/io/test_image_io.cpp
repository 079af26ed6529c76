// Image file I/O: round trips per format and channel count, the one v-flip, content checks,
// atomic writes, and a real texture from the shared data.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <gtest/gtest.h>
#include <png.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <random>

#include "test_paths.h"
#include "texgrad/core/error.h"
#include "texgrad/io/atomic_file.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

using test::tempDir;

/// Random values in [0, 1], with texel (0, 0) fully transparent but coloured when there is an
/// alpha channel (so premultiplication on read or write would show).
Image randomImage(int width, int height, int channels, PixelFormat format, uint32_t seed) {
  Image image(width, height, channels, format);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(0.0f, 1.0f);
  for (float& v : image.pixels) v = value(rng);
  if (channels == 2 || channels == 4) {
    for (int c = 0; c + 1 < channels; ++c) image.at(0, 0, c) = 0.8f;
    image.at(0, 0, channels - 1) = 0.0f;
  }
  return image;
}

/// A smooth image (JPEG's lossy coding keeps it close).
Image smoothImage(int width, int height, int channels) {
  Image image(width, height, channels, PixelFormat::UInt8);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i)
      for (int c = 0; c < channels; ++c)
        image.at(i, j, c) = static_cast<float>(0.5 + 0.4 * std::sin(0.07 * (i + 1) * (c + 1)) *
                                                         std::cos(0.05 * (j + 2 * c)));
  return image;
}

double maxAbsDifference(const Image& a, const Image& b) {
  double worst = 0.0;
  for (size_t k = 0; k < a.pixels.size(); ++k)
    worst = std::max(worst, std::abs(double(a.pixels[k]) - double(b.pixels[k])));
  return worst;
}

std::string readBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

std::vector<std::string> filesIn(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

struct RoundTripCase {
  std::string extension;
  PixelFormat format;
  int channels;
  double tolerance;  ///< largest allowed |read - written| per sample
};

std::string caseName(const ::testing::TestParamInfo<RoundTripCase>& info) {
  static const char* formats[] = {"u8", "u16", "half", "float"};
  return info.param.extension + "_" + formats[static_cast<int>(info.param.format)] + "_" +
         std::to_string(info.param.channels) + "ch";
}

class ImageRoundTrip : public ::testing::TestWithParam<RoundTripCase> {};

TEST_P(ImageRoundTrip, ValuesSizeAndFormatSurvive) {
  const RoundTripCase& c = GetParam();
  const auto dir = tempDir("roundtrip_" + caseName({c, 0}));
  const auto path = dir / ("image." + c.extension);
  // Odd sizes catch row-stride and flip-of-the-middle-row mistakes.
  const Image written = c.extension == "jpg" ? smoothImage(37, 23, c.channels)
                                             : randomImage(37, 23, c.channels, c.format, 7);
  writeImage(path, written, c.format);
  const Image read = readImage(path);
  ASSERT_EQ(read.width, written.width);
  ASSERT_EQ(read.height, written.height);
  ASSERT_EQ(read.channels, written.channels);
  EXPECT_EQ(read.format, c.format);
  EXPECT_LE(maxAbsDifference(read, written), c.tolerance);
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{"image." + c.extension}) << "no temporaries";
}

std::vector<RoundTripCase> roundTripCases() {
  // Quantisation error bounds: half a level for integers, half an ulp at 1 for half floats.
  const double u8 = 0.5 / 255 + 1e-6, u16 = 0.5 / 65535 + 1e-7, half = 0.5 / 1024;
  std::vector<RoundTripCase> cases;
  for (int ch = 1; ch <= 4; ++ch) {
    cases.push_back({"png", PixelFormat::UInt8, ch, u8});
    cases.push_back({"png", PixelFormat::UInt16, ch, u16});
    cases.push_back({"exr", PixelFormat::Float, ch, 0.0});
    cases.push_back({"exr", PixelFormat::Half, ch, half});
    cases.push_back({"tif", PixelFormat::UInt8, ch, u8});
    cases.push_back({"tif", PixelFormat::UInt16, ch, u16});
    cases.push_back({"tif", PixelFormat::Float, ch, 0.0});
  }
  // JPEG is lossy and has no alpha: grey and RGB only, with a bound for a smooth image.
  cases.push_back({"jpg", PixelFormat::UInt8, 1, 0.03});
  cases.push_back({"jpg", PixelFormat::UInt8, 3, 0.06});
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Formats, ImageRoundTrip, ::testing::ValuesIn(roundTripCases()), caseName);

TEST(ImageIo, FormatIsAdjustedToTheExtension) {
  const auto dir = tempDir("format_adjust");
  const Image floats = randomImage(8, 8, 3, PixelFormat::Float, 1);
  writeImage(dir / "a.png", floats);
  EXPECT_EQ(readImage(dir / "a.png").format, PixelFormat::UInt16) << "PNG stores float as 16-bit";
  writeImage(dir / "b.jpg", floats);
  EXPECT_EQ(readImage(dir / "b.jpg").format, PixelFormat::UInt8);
  const Image bytes = randomImage(8, 8, 3, PixelFormat::UInt8, 2);
  writeImage(dir / "c.exr", bytes);
  EXPECT_EQ(readImage(dir / "c.exr").format, PixelFormat::Half) << "EXR stores integers as half";
  writeImage(dir / "d.png", bytes, PixelFormat::UInt16);
  EXPECT_EQ(readImage(dir / "d.png").format, PixelFormat::UInt16) << "explicit format wins";
  writeImage(dir / "f.tif", floats, PixelFormat::Half);
  EXPECT_EQ(readImage(dir / "f.tif").format, PixelFormat::Float) << "TIFF stores half as float";
  writeImage(dir / "e.png", floats, PixelFormat::UInt8);
  EXPECT_EQ(readImage(dir / "e.png").format, PixelFormat::UInt8);
}

TEST(ImageIo, IntegerFormatsClampAndRound) {
  const auto dir = tempDir("clamp_round");
  Image image(4, 1, 1, PixelFormat::UInt8);
  image.pixels = {-0.5f, 1.7f, 100.4f / 255.0f, 100.6f / 255.0f};
  writeImage(dir / "q.png", image);
  const Image read = readImage(dir / "q.png");
  EXPECT_EQ(read.pixels[0], 0.0f);
  EXPECT_EQ(read.pixels[1], 1.0f);
  EXPECT_FLOAT_EQ(read.pixels[2], 100.0f / 255.0f);
  EXPECT_FLOAT_EQ(read.pixels[3], 101.0f / 255.0f);
}

TEST(ImageIo, SampleTextureRoundTripsExactlyAsPng) {
  const auto dir = tempDir("sample_png");
  const Image texture = procedural::sampleTexture(64, 48);
  writeImage(dir / "s.png", texture);
  const Image read = readImage(dir / "s.png");
  ASSERT_EQ(read.pixels.size(), texture.pixels.size());
  for (size_t k = 0; k < read.pixels.size(); ++k)
    ASSERT_EQ(std::lround(read.pixels[k] * 255.0f), std::lround(texture.pixels[k] * 255.0f)) << k;
}

// docs/architecture.md, Conventions: texel row 0 is the bottom of the picture, i.e. the file's
// last scanline.
TEST(ImageIo, TexelRowZeroIsTheLastScanlineOfTheFile) {
  const auto dir = tempDir("flip");
  const int w = 5, h = 4;
  Image image(w, h, 3, PixelFormat::UInt8);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) image.at(i, j, j == 0 ? 0 : 2) = 1.0f;  // row 0 red, others blue
  const auto path = dir / "flip.png";
  writeImage(path, image);

  // The file's scanlines as libpng itself reads them (top first).
  png_image file{};
  file.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(png_image_begin_read_from_file(&file, path.c_str())) << file.message;
  file.format = PNG_FORMAT_RGB;
  std::vector<unsigned char> raw(PNG_IMAGE_SIZE(file));
  ASSERT_TRUE(png_image_finish_read(&file, nullptr, raw.data(), 0, nullptr)) << file.message;
  ASSERT_EQ(raw.size(), size_t(w) * h * 3);
  auto rgb = [&](int scanline, int x) {
    const size_t k = (size_t(scanline) * w + size_t(x)) * 3;
    return std::array<int, 3>{raw[k], raw[k + 1], raw[k + 2]};
  };
  for (int x = 0; x < w; ++x) {
    EXPECT_EQ(rgb(h - 1, x), (std::array<int, 3>{255, 0, 0})) << "last scanline is red";
    EXPECT_EQ(rgb(0, x), (std::array<int, 3>{0, 0, 255})) << "first scanline is blue";
  }
  // And back: the file's last scanline becomes texel row 0.
  const Image read = readImage(path);
  EXPECT_EQ(read.at(2, 0, 0), 1.0f);
  EXPECT_EQ(read.at(2, h - 1, 0), 0.0f);
}

TEST(ImageIo, FileScanlineZeroBecomesTheTopTexelRow) {
  const auto dir = tempDir("flip_read");
  const int w = 3, h = 6;
  std::vector<float> raw(size_t(w) * h, 0.0f);
  for (int x = 0; x < w; ++x) raw[size_t(x)] = 1.0f;  // first scanline white
  const auto path = dir / "top.exr";
  {  // Written by OpenEXR itself: scanline 0 is the top of the picture.
    Imf::Header header(w, h);
    header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
    Imf::FrameBuffer buffer;
    buffer.insert("Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(raw.data()), sizeof(float),
                                  w * sizeof(float)));
    Imf::OutputFile output(path.c_str(), header);
    output.setFrameBuffer(buffer);
    output.writePixels(h);
  }
  const Image read = readImage(path);
  for (int x = 0; x < w; ++x) {
    EXPECT_EQ(read.at(x, h - 1), 1.0f);
    EXPECT_EQ(read.at(x, 0), 0.0f);
  }
}

TEST(ImageIo, ContentMustMatchTheExtension) {
  const auto dir = tempDir("magic");
  writeImage(dir / "real.png", procedural::sampleTexture(8, 8));
  std::filesystem::copy_file(dir / "real.png", dir / "fake.jpg");
  try {
    readImage(dir / "fake.jpg");
    FAIL() << "a PNG named .jpg must be rejected";
  } catch (const InvalidInputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("fake.jpg"), std::string::npos) << what;
    EXPECT_NE(what.find("not a JPEG"), std::string::npos) << what;
    EXPECT_NE(what.find("PNG"), std::string::npos) << what;
  }
  writeBytes(dir / "text.png", "this is not an image at all");
  try {
    readImage(dir / "text.png");
    FAIL() << "text named .png must be rejected";
  } catch (const InvalidInputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("text.png is not a PNG file"), std::string::npos) << what;
    EXPECT_NE(what.find("text"), std::string::npos) << what;
  }
  writeBytes(dir / "empty.exr", "");
  EXPECT_THROW(readImage(dir / "empty.exr"), InvalidInputError);
  writeBytes(dir / "empty.tif", "");
  EXPECT_THROW(readImage(dir / "empty.tif"), InvalidInputError);
}

void expectOneLineInvalidInput(const std::filesystem::path& path) {
  try {
    readImage(path);
    ADD_FAILURE() << path << " must be rejected";
  } catch (const InvalidInputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path.filename().string()), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
  }
}

TEST(ImageIo, TruncatedFilesAreInvalidInputAndPrintNothing) {
  const auto dir = tempDir("truncated");
  for (const char* ext : {"png", "jpg", "exr", "tif"}) {
    const auto full = dir / (std::string("full.") + ext);
    writeImage(full, procedural::sampleTexture(64, 64));
    const std::string bytes = readBytes(full);
    for (size_t keep : {bytes.size() / 2, size_t{40}}) {
      const auto cut = dir / ("cut" + std::to_string(keep) + "." + ext);
      writeBytes(cut, bytes.substr(0, keep));
      ::testing::internal::CaptureStderr();
      expectOneLineInvalidInput(cut);
      EXPECT_EQ(::testing::internal::GetCapturedStderr(), "") << "library code prints nothing";
    }
  }
}

TEST(ImageIo, MalformedPngsAreRejectedBeforeLibpngSeesThem) {
  const auto dir = tempDir("malformed_png");
  writeImage(dir / "good.png", procedural::sampleTexture(16, 16));
  std::string bytes = readBytes(dir / "good.png");
  // IHDR data starts at byte 16: zero the width (checksum now wrong too).
  std::string zero = bytes;
  std::fill(zero.begin() + 16, zero.begin() + 20, '\0');
  writeBytes(dir / "zero.png", zero);
  std::string flipped = bytes;
  flipped[bytes.size() / 2] = static_cast<char>(flipped[bytes.size() / 2] ^ 0x40);
  writeBytes(dir / "flipped.png", flipped);
  ::testing::internal::CaptureStderr();
  expectOneLineInvalidInput(dir / "zero.png");
  expectOneLineInvalidInput(dir / "flipped.png");
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

TEST(ImageIo, MissingFileIsIoError) {
  const auto dir = tempDir("missing");
  try {
    readImage(dir / "nothere.png");
    FAIL() << "reading a missing file must throw";
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("nothere.png"), std::string::npos) << what;
    EXPECT_NE(what.find("No such file"), std::string::npos) << what;
  }
}

TEST(ImageIo, MoreThanFourChannelsIsUnsupported) {
  const auto dir = tempDir("five_channels");
  const auto path = dir / "five.exr";
  std::vector<float> raw(4 * 4, 0.5f);
  {
    Imf::Header header(4, 4);
    Imf::FrameBuffer buffer;
    for (const char* name : {"R", "G", "B", "A", "Z"}) {
      header.channels().insert(name, Imf::Channel(Imf::FLOAT));
      buffer.insert(name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(raw.data()),
                                     sizeof(float), 4 * sizeof(float)));
    }
    Imf::OutputFile output(path.c_str(), header);
    output.setFrameBuffer(buffer);
    output.writePixels(4);
  }
  EXPECT_THROW(readImage(path), UnsupportedError);
  EXPECT_THROW(writeImage(dir / "five.png", Image(4, 4, 5)), UnsupportedError);
}

TEST(ImageIo, UnwritableRequestsThrowAndWriteNothing) {
  const auto dir = tempDir("unwritable");
  EXPECT_THROW(writeImage(dir / "image.bmp", Image(4, 4, 3)), UnsupportedError);
  EXPECT_THROW(writeImage(dir / "alpha.jpg", Image(4, 4, 4)), UnsupportedError);
  EXPECT_THROW(writeImage(dir / "empty.png", Image()), InvalidInputError);
  try {
    writeImage(dir / "no_such_folder" / "x.png", Image(4, 4, 3));
    FAIL() << "writing into a missing folder must throw";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_folder"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(filesIn(dir).empty());
}

TEST(AtomicFile, TemporaryIsBesideTheTargetAndKeepsTheExtension) {
  const auto dir = tempDir("atomic_name");
  std::filesystem::path seen;
  writeAtomically(dir / "out.png", [&](const std::filesystem::path& temporary) {
    seen = temporary;
    writeBytes(temporary, "new");
  });
  EXPECT_EQ(seen.parent_path(), dir);
  EXPECT_EQ(seen.extension(), ".png");
  EXPECT_EQ(seen.filename().string().front(), '.') << "hidden: " << seen;
  EXPECT_NE(seen.filename(), "out.png");
  EXPECT_EQ(readBytes(dir / "out.png"), "new");
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{"out.png"});
}

TEST(AtomicFile, ThrowingWriterLeavesTargetUntouchedAndNoTemporary) {
  const auto dir = tempDir("atomic_throw");
  writeBytes(dir / "out.txt", "old contents");
  struct WriterFailed {};
  EXPECT_THROW(writeAtomically(dir / "out.txt",
                               [&](const std::filesystem::path& temporary) {
                                 writeBytes(temporary, "half of the new");
                                 throw WriterFailed{};
                               }),
               WriterFailed);
  EXPECT_EQ(readBytes(dir / "out.txt"), "old contents");
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFile, PendingTemporariesAreRemovedOnRequestAndFinishedOnesAreNot) {
  const auto dir = tempDir("atomic_pending");
  writeAtomically(dir / "done.txt", [&](const std::filesystem::path& t) { writeBytes(t, "1"); });
  // What an interrupt handler does in the middle of a write: the temporary goes, the rename then
  // fails, and the finished output of the earlier write is left alone.
  EXPECT_THROW(writeAtomically(dir / "out.txt",
                               [&](const std::filesystem::path& temporary) {
                                 writeBytes(temporary, "half of the new");
                                 removePendingTemporaries();
                               }),
               IoError);
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{"done.txt"});
}

TEST(AtomicFile, ReplacesAnExistingImage) {
  const auto dir = tempDir("atomic_replace");
  writeImage(dir / "img.png", Image(4, 4, 1, PixelFormat::UInt8));
  Image white(4, 4, 1, PixelFormat::UInt8);
  std::fill(white.pixels.begin(), white.pixels.end(), 1.0f);
  writeImage(dir / "img.png", white);
  EXPECT_EQ(readImage(dir / "img.png").pixels, white.pixels);
  EXPECT_EQ(filesIn(dir), std::vector<std::string>{"img.png"});
}

TEST(AtomicFile, MissingFolderIsIoErrorNamingIt) {
  const auto dir = tempDir("atomic_missing");
  bool called = false;
  try {
    writeAtomically(dir / "absent" / "out.txt",
                    [&](const std::filesystem::path&) { called = true; });
    FAIL() << "a missing folder must throw";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "absent").string()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(called);
}

TEST(ImageIo, ReadsFromMemoryLikeFromFile) {
  const auto dir = tempDir("memory");
  const Image rgb = randomImage(13, 9, 3, PixelFormat::UInt8, 3);
  for (const char* name : {"m.png", "m.jpg", "m.exr", "m.tif"}) {
    writeImage(dir / name, rgb);
    const std::string text = readBytes(dir / name);
    const std::vector<unsigned char> bytes(text.begin(), text.end());
    const Image fromFile = readImage(dir / name);
    const Image fromMemory = readImageFromMemory(bytes, name);
    EXPECT_EQ(fromMemory.width, 13) << name;
    EXPECT_EQ(fromMemory.format, fromFile.format) << name;
    EXPECT_EQ(fromMemory.pixels, fromFile.pixels) << name;
  }
  const std::string junk = "GIF89a not supported";
  try {
    readImageFromMemory({junk.begin(), junk.end()}, "model.glb (embedded baseColor texture)");
    FAIL() << "unknown bytes must be rejected";
  } catch (const InvalidInputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("model.glb"), std::string::npos) << what;
    EXPECT_NE(what.find("GIF"), std::string::npos) << what;
  }
  EXPECT_THROW(readImageFromMemory({}, "nothing"), InvalidInputError);
}

TEST(ImageIo, ParsePixelFormat) {
  EXPECT_EQ(parsePixelFormat("8"), PixelFormat::UInt8);
  EXPECT_EQ(parsePixelFormat("16"), PixelFormat::UInt16);
  EXPECT_EQ(parsePixelFormat("half"), PixelFormat::Half);
  EXPECT_EQ(parsePixelFormat("float"), PixelFormat::Float);
  EXPECT_THROW(parsePixelFormat("12"), InvalidInputError);
  EXPECT_THROW(parsePixelFormat(""), InvalidInputError);
}

TEST(ImageIo, ReadsTheSpotTexture) {
  const auto path = test::sharedData() / "spot" / "spot_texture.png";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data missing: " << path;
  const Image image = readImage(path);
  EXPECT_EQ(image.width, 1024);
  EXPECT_EQ(image.height, 1024);
  EXPECT_EQ(image.channels, 3);
  EXPECT_EQ(image.format, PixelFormat::UInt8);
  const auto [lo, hi] = std::minmax_element(image.pixels.begin(), image.pixels.end());
  EXPECT_GE(*lo, 0.0f);
  EXPECT_LE(*hi, 1.0f);
  EXPECT_LT(*lo, *hi);
}

}  // namespace
}  // namespace texgrad
