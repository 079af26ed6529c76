// requireUvsInImage: the UV area inside [0, 1]^2 is exact, and only an atlas wholly outside the
// image is refused.
#include <gtest/gtest.h>

#include <string>

#include "texgrad/atlas/image_coverage.h"
#include "texgrad/core/error.h"
#include "texgrad/io/procedural.h"

namespace texgrad {
namespace {

TEST(ImageCoverage, AreaInsideTheImageIsTheClippedUvArea) {
  EXPECT_NEAR(uvAreaInImage(procedural::square()), 1.0, 1e-12);
  // Half of the square lies right of u = 1, a quarter of this one above v = 1 and right of u = 1.
  EXPECT_NEAR(uvAreaInImage(procedural::square(1.0, 1.0, 0.5, 0.0)), 0.5, 1e-12);
  EXPECT_NEAR(uvAreaInImage(procedural::square(1.0, 1.0, 0.5, 0.5)), 0.25, 1e-12);
  // A square larger than the image covers all of it once.
  EXPECT_NEAR(uvAreaInImage(procedural::square(3.0, 3.0, -1.0, -1.0)), 1.0, 1e-12);
  // Touching the image along an edge or at a corner covers nothing, exactly.
  EXPECT_EQ(uvAreaInImage(procedural::square(1.0, 1.0, 1.0, 0.0)), 0.0);
  EXPECT_EQ(uvAreaInImage(procedural::square(1.0, 1.0, 0.0, -1.0)), 0.0);
  EXPECT_EQ(uvAreaInImage(procedural::square(1.0, 1.0, -1.0, -1.0)), 0.0);
  EXPECT_EQ(uvAreaInImage(procedural::square(0.3, 0.7, 1.0 / 3.0, 1.0)), 0.0);
}

TEST(ImageCoverage, OnlyAnAtlasWhollyOutsideTheImageIsRefused) {
  EXPECT_NO_THROW(requireUvsInImage(procedural::square()));
  EXPECT_NO_THROW(requireUvsInImage(procedural::square(1.0, 1.0, 0.999, 0.0)));
  try {
    requireUvsInImage(procedural::square(1.0, 1.0, 1.0, 0.25));
    FAIL() << "UVs in u [1, 2] must be refused";
  } catch (const InvalidInputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("UVs span u [1, 2] x v [0.25, 1.25]"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace texgrad
