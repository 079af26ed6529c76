// Normal-map decoding/encoding around processing (apps: filter --normal-map).
#include "texgrad/apps/normal_map.h"

#include <cmath>

#include "texgrad/core/error.h"

namespace texgrad {

Image decodeNormalMap(const Image& encoded) {
  if (encoded.channels < 3)
    throw InvalidInputError("a normal map needs 3 channels (RGB); this image has " +
                            std::to_string(encoded.channels));
  Image vectors(encoded.width, encoded.height, 3, encoded.format);
  for (int j = 0; j < encoded.height; ++j)
    for (int i = 0; i < encoded.width; ++i)
      for (int c = 0; c < 3; ++c) vectors.at(i, j, c) = 2.0f * encoded.at(i, j, c) - 1.0f;
  renormalize(vectors);
  return vectors;
}

void renormalize(Image& vectors) {
  for (int j = 0; j < vectors.height; ++j)
    for (int i = 0; i < vectors.width; ++i) {
      const double x = vectors.at(i, j, 0), y = vectors.at(i, j, 1), z = vectors.at(i, j, 2);
      const double length = std::sqrt(x * x + y * y + z * z);
      if (length > 0.0 && std::isfinite(length)) {
        for (int c = 0; c < 3; ++c)
          vectors.at(i, j, c) = static_cast<float>(vectors.at(i, j, c) / length);
      } else {
        vectors.at(i, j, 0) = 0.0f, vectors.at(i, j, 1) = 0.0f, vectors.at(i, j, 2) = 1.0f;
      }
    }
}

Image encodeNormalMap(const Image& vectors, const Image& like) {
  Image encoded = like;
  for (int j = 0; j < like.height; ++j)
    for (int i = 0; i < like.width; ++i)
      for (int c = 0; c < 3; ++c) encoded.at(i, j, c) = 0.5f * (vectors.at(i, j, c) + 1.0f);
  return encoded;
}

}  // namespace texgrad
