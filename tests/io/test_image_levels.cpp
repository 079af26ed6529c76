// 8-bit levels of an image: exact for what readImage decodes from an 8-bit file (every level),
// refused for values that are not levels, and back to the same floats bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "test_paths.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/image_levels.h"

namespace texgrad {
namespace {

/// A 16 x 16 grey image holding every 8-bit level once, as 8-bit.
Image everyLevel() {
  constexpr int kSide = 16;
  Image image(kSide, kSide, 1, PixelFormat::UInt8);
  for (size_t k = 0; k < image.pixels.size(); ++k) image.pixels[k] = static_cast<float>(k) / 255.0f;
  return image;
}

/// `image` written to an 8-bit PNG and read back as readImage decodes it.
Image readBack(const Image& image) {
  const auto dir = test::tempDir("image_levels");
  writeImage(dir / "levels.png", image);
  Image read = readImage(dir / "levels.png");
  std::filesystem::remove_all(dir);
  return read;
}

TEST(ImageLevels, EveryLevelReadFromAnEightBitFileIsExactAndComesBackBitForBit) {
  const Image read = readBack(everyLevel());
  ASSERT_EQ(read.format, PixelFormat::UInt8);
  const std::optional<std::vector<uint8_t>> bytes = exactByteLevels(read);
  ASSERT_TRUE(bytes.has_value()) << "a decoded 8-bit value is not level / 255";
  for (size_t k = 0; k < bytes->size(); ++k) EXPECT_EQ((*bytes)[k], k);
  EXPECT_EQ(valuesOfByteLevels(*bytes), read.pixels);
}

TEST(ImageLevels, RefusesOtherFormatsAndValuesThatAreNotLevels) {
  Image image = readBack(everyLevel());
  image.format = PixelFormat::UInt16;
  EXPECT_FALSE(exactByteLevels(image).has_value());
  image.format = PixelFormat::UInt8;
  ASSERT_TRUE(exactByteLevels(image).has_value());
  const float level7 = readBack(image).pixels[7];
  for (float bad : {0.5f, -1.0f / 255.0f, 256.0f / 255.0f, std::numeric_limits<float>::quiet_NaN(),
                    std::nextafter(level7, 1.0f)}) {
    Image changed = image;
    changed.pixels[7] = bad;
    EXPECT_FALSE(exactByteLevels(changed).has_value()) << bad;
  }
}

}  // namespace
}  // namespace texgrad
