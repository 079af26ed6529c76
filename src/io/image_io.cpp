// Image file I/O: where a file's content is checked against its extension and handed to the
// codec of its format (image_codecs.h: libpng, libjpeg-turbo, OpenEXR, libtiff), which turns file
// rows (top first) into texel rows (bottom first) and back (docs/architecture.md, Conventions).
#include "texgrad/io/image_io.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cstring>
#include <fstream>
#include <iterator>
#include <span>
#include <string_view>

#include "image_codecs.h"
#include "texgrad/core/error.h"
#include "texgrad/io/atomic_file.h"

namespace texgrad {
namespace {

/// Bytes looked at to describe unrecognised content.
constexpr size_t kMagicBytes = 16;
/// Channels an image file holds: grey, grey + alpha, RGB, RGBA.
constexpr int kMaxChannels = 4;

/// File formats texgrad recognises by extension and by content.
enum class FileKind { Png, Jpeg, Exr, Tiff, Unknown };

std::string_view kindName(FileKind kind) {
  switch (kind) {
    case FileKind::Png:
      return "PNG";
    case FileKind::Jpeg:
      return "JPEG";
    case FileKind::Exr:
      return "OpenEXR";
    case FileKind::Tiff:
      return "TIFF";
    case FileKind::Unknown:
      break;
  }
  return "unknown";
}

/// "a PNG", "an OpenEXR".
std::string withArticle(std::string_view noun) {
  const bool vowel =
      !noun.empty() && std::string_view("AEIOUaeiou").find(noun[0]) != std::string_view::npos;
  return (vowel ? "an " : "a ") + std::string(noun);
}

std::string lowercase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

FileKind kindOfExtension(const std::filesystem::path& path) {
  const std::string ext = lowercase(path.extension().string());
  if (ext == ".png") return FileKind::Png;
  if (ext == ".jpg" || ext == ".jpeg" || ext == ".jpe") return FileKind::Jpeg;
  if (ext == ".exr") return FileKind::Exr;
  if (ext == ".tif" || ext == ".tiff") return FileKind::Tiff;
  return FileKind::Unknown;
}

bool startsWith(std::span<const unsigned char> bytes, std::string_view magic) {
  return bytes.size() >= magic.size() && std::memcmp(bytes.data(), magic.data(), magic.size()) == 0;
}

/// Format from the first bytes (the signatures of the PNG, JFIF, OpenEXR and TIFF specs).
FileKind kindOfContent(std::span<const unsigned char> bytes) {
  using namespace std::string_view_literals;
  if (startsWith(bytes, "\x89PNG\r\n\x1a\n"sv)) return FileKind::Png;
  if (startsWith(bytes, "\xff\xd8\xff"sv)) return FileKind::Jpeg;
  if (startsWith(bytes, "\x76\x2f\x31\x01"sv)) return FileKind::Exr;
  if (startsWith(bytes, "II*\0"sv) || startsWith(bytes, "MM\0*"sv) ||  // classic TIFF
      startsWith(bytes, "II+\0"sv) || startsWith(bytes, "MM\0+"sv))    // BigTIFF
    return FileKind::Tiff;
  return FileKind::Unknown;
}

/// Human description of what the bytes look like, for "X is not a PNG file (...)" messages.
std::string describeContent(std::span<const unsigned char> bytes) {
  using namespace std::string_view_literals;
  bytes = bytes.first(std::min(bytes.size(), kMagicBytes));
  if (bytes.empty()) return "an empty file";
  if (const FileKind kind = kindOfContent(bytes); kind != FileKind::Unknown)
    return withArticle(kindName(kind)) + " image";
  if (startsWith(bytes, "GIF8"sv)) return "a GIF image";
  if (startsWith(bytes, "BM"sv)) return "a BMP image";
  if (startsWith(bytes, "#?RADIANCE"sv) || startsWith(bytes, "#?RGBE"sv))
    return "a Radiance HDR image";
  if (startsWith(bytes, "RIFF"sv) && bytes.size() >= 12 &&
      std::memcmp(bytes.data() + 8, "WEBP", 4) == 0)
    return "a WebP image";
  if (startsWith(bytes, "glTF"sv)) return "a binary glTF file";
  const bool text = std::all_of(bytes.begin(), bytes.end(), [](unsigned char c) {
    return std::isprint(c) || c == '\n' || c == '\r' || c == '\t';
  });
  if (text) return "text";
  return "unrecognised binary data";
}

/// Decodes `bytes`, whose format is `kind`, with that format's codec.
Image decodeBytes(codec::Bytes bytes, FileKind kind, const std::string& name) {
  switch (kind) {
    case FileKind::Png:
      return codec::decodePng(bytes, name);
    case FileKind::Jpeg:
      return codec::decodeJpeg(bytes, name);
    case FileKind::Exr:
      return codec::decodeExr(bytes, name);
    case FileKind::Tiff:
      return codec::decodeTiff(bytes, name);
    case FileKind::Unknown:
      break;
  }
  throw InvalidInputError(name + " is not a PNG, JPEG, OpenEXR or TIFF image (content looks like " +
                          describeContent(bytes) + ")");
}

/// The whole file (images are decoded from memory, so the content is read exactly once).
std::vector<unsigned char> readFileBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open " + path.string() + ": permission denied or unreadable");
  std::vector<unsigned char> bytes{std::istreambuf_iterator<char>(in),
                                   std::istreambuf_iterator<char>()};
  if (in.bad()) throw IoError("reading " + path.string() + " failed");
  return bytes;
}

/// Format actually stored for a requested one: JPEG is 8-bit only, PNG integer only (float goes
/// to 16 bits), OpenEXR floating point only (integer goes to half), TIFF has no half (float).
PixelFormat storableFormat(FileKind kind, PixelFormat requested) {
  const bool isInteger = requested == PixelFormat::UInt8 || requested == PixelFormat::UInt16;
  switch (kind) {
    case FileKind::Jpeg:
      return PixelFormat::UInt8;
    case FileKind::Png:
      return isInteger ? requested : PixelFormat::UInt16;
    case FileKind::Exr:
      return isInteger ? PixelFormat::Half : requested;
    case FileKind::Tiff:
      return requested == PixelFormat::Half ? PixelFormat::Float : requested;
    case FileKind::Unknown:
      break;
  }
  return requested;
}

/// Throws UnsupportedError naming `path` unless its extension is one writeImage writes.
FileKind writableKind(const std::filesystem::path& path) {
  const FileKind kind = kindOfExtension(path);
  if (kind == FileKind::Unknown)
    throw UnsupportedError("cannot write " + path.string() + ": unknown image extension '" +
                           path.extension().string() + "'; use .png, .jpg, .exr or .tif");
  return kind;
}

/// Writes `image` as `format` (already storable) into `temporary`, with the codec of `kind`.
void encode(const std::filesystem::path& temporary, const std::filesystem::path& target,
            FileKind kind, const Image& image, PixelFormat format) {
  const std::string where = "cannot write " + target.string() + ": ";
  switch (kind) {
    case FileKind::Png:
      return codec::writePng(temporary, image, format != PixelFormat::UInt8, where);
    case FileKind::Jpeg:
      return codec::writeJpeg(temporary, image, where);
    case FileKind::Exr:
      return codec::writeExr(temporary, image, format == PixelFormat::Half, where);
    case FileKind::Tiff:
      return codec::writeTiff(temporary, image, format, where);
    case FileKind::Unknown:
      break;
  }
  throw UnsupportedError(where + "unknown image extension");
}

}  // namespace

Image readImage(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw IoError("cannot open " + name + ": No such file");
  if (std::filesystem::is_directory(path, ec))
    throw IoError("cannot open " + name + ": it is a folder, not an image");

  const std::vector<unsigned char> bytes = readFileBytes(path);
  const FileKind expected = kindOfExtension(path), content = kindOfContent(bytes);
  if (expected != FileKind::Unknown && content != expected)
    throw InvalidInputError(name + " is not " + withArticle(kindName(expected)) +
                            " file (content looks like " + describeContent(bytes) + ")");
  if (content == FileKind::Unknown)
    throw UnsupportedError("cannot read " + name + ": its content looks like " +
                           describeContent(bytes) +
                           "; texgrad reads PNG, JPEG, OpenEXR and TIFF (convert it first, e.g. "
                           "oiiotool IN -o OUT.png)");
  return decodeBytes(bytes, content, name);
}

std::pair<int, int> readImageSize(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw IoError("cannot open " + name + ": No such file");
  std::array<unsigned char, kMagicBytes> head{};
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open " + name + ": permission denied or unreadable");
  in.read(reinterpret_cast<char*>(head.data()), static_cast<std::streamsize>(head.size()));
  const std::span<const unsigned char> start(head.data(), static_cast<size_t>(in.gcount()));
  const FileKind expected = kindOfExtension(path), content = kindOfContent(start);
  if (expected != FileKind::Unknown && content != expected)
    throw InvalidInputError(name + " is not " + withArticle(kindName(expected)) +
                            " file (content looks like " + describeContent(start) + ")");
  switch (content) {
    case FileKind::Png:
      return codec::pngSize(path);
    case FileKind::Jpeg:
      return codec::jpegSize(path);
    case FileKind::Exr:
      return codec::exrSize(path);
    case FileKind::Tiff:
      return codec::tiffSize(path);
    case FileKind::Unknown:
      break;
  }
  throw UnsupportedError("cannot read " + name + ": its content looks like " +
                         describeContent(start) + "; texgrad reads PNG, JPEG, OpenEXR and TIFF");
}

Image readImageFromMemory(const std::vector<unsigned char>& bytes, const std::string& name) {
  return decodeBytes(bytes, kindOfContent(bytes), name);
}

PixelFormat writeImage(const std::filesystem::path& path, const Image& image,
                       std::optional<PixelFormat> format) {
  const std::string name = path.string();
  if (image.width <= 0 || image.height <= 0 || image.channels <= 0)
    throw InvalidInputError("cannot write " + name + ": the image is empty");
  if (image.channels > kMaxChannels)
    throw UnsupportedError("cannot write " + name + ": " + std::to_string(image.channels) +
                           " channels; image files hold 1 to 4");
  if (image.pixels.size() != image.index(0, image.height))
    throw InvalidInputError("cannot write " + name + ": pixel buffer size does not match " +
                            std::to_string(image.width) + " x " + std::to_string(image.height) +
                            " x " + std::to_string(image.channels));
  const FileKind kind = writableKind(path);
  if (kind == FileKind::Jpeg && (image.channels == 2 || image.channels == 4))
    throw UnsupportedError("cannot write " + name + ": JPEG has no alpha channel; use .png, " +
                           ".exr or .tif to keep all " + std::to_string(image.channels) +
                           " channels");
  const PixelFormat stored = storableFormat(kind, format.value_or(image.format));
  writeAtomically(path, [&](const std::filesystem::path& temporary) {
    encode(temporary, path, kind, image, stored);
  });
  return stored;
}

namespace {

/// The depths a kind of file stores as asked (storableFormat is the rule), for messages.
std::string formatsHeld(FileKind kind) {
  std::string held;
  for (PixelFormat f :
       {PixelFormat::UInt8, PixelFormat::UInt16, PixelFormat::Half, PixelFormat::Float})
    if (storableFormat(kind, f) == f)
      held += (held.empty() ? "" : ", ") + std::string(pixelFormatName(f));
  return held;
}

}  // namespace

void checkImageOutput(const std::filesystem::path& path, std::optional<PixelFormat> requested) {
  const FileKind kind = writableKind(path);
  if (requested && storableFormat(kind, *requested) != *requested)
    throw InvalidInputError("cannot write " + path.string() + " as " +
                            std::string(pixelFormatName(*requested)) + ": " +
                            std::string(kindName(kind)) + " holds " + formatsHeld(kind) +
                            "; pick another bit depth or extension (.png: 8/16, .exr: "
                            "half/float, .tif: 8/16/float)");
  checkWritableTarget(path);
}

std::string_view pixelFormatName(PixelFormat format) {
  switch (format) {
    case PixelFormat::UInt8:
      return "8-bit";
    case PixelFormat::UInt16:
      return "16-bit";
    case PixelFormat::Half:
      return "half float";
    case PixelFormat::Float:
      return "float";
  }
  return "";
}

PixelFormat parsePixelFormat(const std::string& text) {
  const std::string key = lowercase(text);
  if (key == "8") return PixelFormat::UInt8;
  if (key == "16") return PixelFormat::UInt16;
  if (key == "half") return PixelFormat::Half;
  if (key == "float") return PixelFormat::Float;
  throw InvalidInputError("unknown pixel format '" + text + "'; use 8, 16, half or float");
}

}  // namespace texgrad
