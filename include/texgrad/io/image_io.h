// Image file I/O (PNG 8/16-bit, JPEG, EXR, TIFF) through each format's library, with the one
// v-flip.
#pragma once

#include <filesystem>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "texgrad/io/image.h"

namespace texgrad {

/// Reads an image file into texel order (row 0 = bottom). Checks that the file's content matches
/// its extension; throws IoError / InvalidInputError naming the file on any problem.
Image readImage(const std::filesystem::path& path);

/// The width and height of an image file, read from its header (no pixels are decoded); throws
/// IoError if it is missing, InvalidInputError if its header cannot be read, UnsupportedError if
/// it is none of PNG, JPEG, OpenEXR and TIFF.
std::pair<int, int> readImageSize(const std::filesystem::path& path);

/// Decodes an image held in memory (e.g. embedded in a GLB); `name` is used in messages.
Image readImageFromMemory(const std::vector<unsigned char>& bytes, const std::string& name);

/// Writes an image atomically (temporary file in the same folder, then rename). The format
/// defaults to image.format; it is adjusted to what the extension supports (JPEG: 8-bit; PNG: 8
/// or 16 bits; OpenEXR: half or float; TIFF: no half). Returns the format stored.
PixelFormat writeImage(const std::filesystem::path& path, const Image& image,
                       std::optional<PixelFormat> format = std::nullopt);

/// Checks before any work that writeImage can write `path`: a known image extension, a format
/// `requested` by the user that the file type holds as it is (no silent adjustment), and a
/// writable folder (checkWritableTarget). Throws UnsupportedError, InvalidInputError or IoError.
void checkImageOutput(const std::filesystem::path& path,
                      std::optional<PixelFormat> requested = std::nullopt);

/// "8-bit", "16-bit", "half float", "float".
std::string_view pixelFormatName(PixelFormat format);

/// Parses "8", "16", "half", "float" into a PixelFormat; throws InvalidInputError otherwise.
PixelFormat parsePixelFormat(const std::string& text);

}  // namespace texgrad
