// Image file I/O through OpenImageIO: where file rows (top first) become texel rows (bottom first)
// and back (docs/architecture.md, Conventions), and where content is checked against the file's
// extension.
#include "texgrad/io/image_io.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <span>
#include <string_view>
#include <type_traits>

#include "image_spec.h"
#include "texgrad/core/error.h"
#include "texgrad/io/atomic_file.h"

namespace texgrad {
namespace {

/// Bytes looked at to describe unrecognised content.
constexpr size_t kMagicBytes = 16;
/// Largest image accepted (2^30 texels, e.g. 32768 x 32768): beyond it the float copy alone
/// needs more than 4 GB per channel, which is a mistake rather than a texture.
constexpr int64_t kMaxTexels = int64_t{1} << 30;
/// Channels texgrad processes: grey, grey + alpha, RGB, RGBA.
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

/// Extension OpenImageIO associates with a kind (used to name in-memory images).
std::string_view kindExtension(FileKind kind) {
  switch (kind) {
    case FileKind::Png:
      return "png";
    case FileKind::Jpeg:
      return "jpg";
    case FileKind::Exr:
      return "exr";
    case FileKind::Tiff:
      return "tif";
    case FileKind::Unknown:
      break;
  }
  return "";
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

PixelFormat formatOf(OIIO::TypeDesc type) {
  switch (type.basetype) {
    case OIIO::TypeDesc::UINT8:
    case OIIO::TypeDesc::INT8:
      return PixelFormat::UInt8;
    case OIIO::TypeDesc::UINT16:
    case OIIO::TypeDesc::INT16:
      return PixelFormat::UInt16;
    case OIIO::TypeDesc::HALF:
      return PixelFormat::Half;
    default:
      return PixelFormat::Float;
  }
}

OIIO::TypeDesc typeOf(PixelFormat format) {
  switch (format) {
    case PixelFormat::UInt8:
      return OIIO::TypeDesc::UINT8;
    case PixelFormat::UInt16:
      return OIIO::TypeDesc::UINT16;
    case PixelFormat::Half:
      return OIIO::TypeDesc::HALF;
    case PixelFormat::Float:
      break;
  }
  return OIIO::TypeDesc::FLOAT;
}

/// Reader hints: keep colour and alpha as stored (no premultiplication), so values round-trip.
OIIO::ImageSpec readerConfig() {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  return config;
}

/// Swaps rows j and H-1-j: file order (top first) <-> texel order (bottom first).
template <typename T>
void flipRows(std::vector<T>& data, int width, int height, int channels) {
  const auto row = static_cast<ptrdiff_t>(width) * channels;
  for (int j = 0; j < height / 2; ++j) {
    auto a = data.begin() + j * row;
    auto b = data.begin() + (height - 1 - j) * row;
    std::swap_ranges(a, a + row, b);
  }
}

/// Reads subimage 0 of an opened input into texel order; `name` is used in messages.
Image decode(OIIO::ImageInput& input, const std::string& name) {
  const OIIO::ImageSpec& spec = input.spec();
  if (spec.width <= 0 || spec.height <= 0)
    throw InvalidInputError(name + " declares an empty image (" + std::to_string(spec.width) +
                            " x " + std::to_string(spec.height) + "); re-export the texture");
  if (spec.depth > 1)
    throw UnsupportedError(name + " is a volume image (depth " + std::to_string(spec.depth) +
                           "); texgrad needs a 2-D texture");
  if (spec.nchannels < 1 || spec.nchannels > kMaxChannels)
    throw UnsupportedError(name + " has " + std::to_string(spec.nchannels) +
                           " channels; texgrad handles 1 to 4 (grey, grey+alpha, RGB, RGBA)");
  if (spec.x != spec.full_x || spec.y != spec.full_y || spec.width != spec.full_width ||
      spec.height != spec.full_height)
    throw UnsupportedError(name +
                           " has a data window different from its display window; "
                           "crop it to the full image first (oiiotool IN --croptofull -o OUT)");
  if (static_cast<int64_t>(spec.width) * spec.height > kMaxTexels)
    throw UnsupportedError(name + " is " + std::to_string(spec.width) + " x " +
                           std::to_string(spec.height) + " texels; texgrad handles at most " +
                           std::to_string(kMaxTexels) + " texels");

  Image image(spec.width, spec.height, spec.nchannels, formatOf(spec.format));
  // Some readers (TIFF strips, JPEG's premature end) record an error yet return success.
  if (!input.read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data()) ||
      input.has_error())
    throw InvalidInputError(name + " is truncated or corrupt: " + oneLine(input.geterror()));
  flipRows(image.pixels, image.width, image.height, image.channels);
  return image;
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

uint32_t bigEndian32(const unsigned char* p) {
  return uint32_t{p[0]} << 24 | uint32_t{p[1]} << 16 | uint32_t{p[2]} << 8 | uint32_t{p[3]};
}

/// CRC-32 of the PNG specification (ISO 3309 polynomial), over chunk type and data.
uint32_t pngCrc(std::span<const unsigned char> bytes) {
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

/// Checks a PNG's chunk structure (PNG spec sec. 5): complete chunks with valid checksums, a
/// sane non-empty IHDR first, IDAT data and a closing IEND. libpng prints its errors to stderr
/// (OpenImageIO installs no handler), so malformed files are rejected here, with a message.
void checkPngStructure(std::span<const unsigned char> bytes, const std::string& name) {
  constexpr size_t kSignature = 8, kChunkOverhead = 12, kIhdrLength = 13;
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

/// Opens `bytes` (whose format is `kind`) with OpenImageIO and decodes them.
Image decodeBytes(std::span<const unsigned char> bytes, FileKind kind, const std::string& name) {
  if (kind == FileKind::Png) checkPngStructure(bytes, name);
  // The reader is chosen by the extension of this stand-in name; the bytes come from the proxy.
  const std::string proxyName = "texgrad-memory." + std::string(kindExtension(kind));
  OIIO::Filesystem::IOMemReader proxy(bytes.data(), bytes.size());
  OIIO::ImageSpec config = readerConfig();
  // OIIO 2.4's readers take the proxy from this hint (the open() argument alone is dropped when
  // a config is given).
  OIIO::Filesystem::IOProxy* proxyPointer = &proxy;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxyPointer);
  auto input = OIIO::ImageInput::open(proxyName, &config, &proxy);
  if (!input)
    throw InvalidInputError(name + " is truncated or corrupt: " + oneLine(OIIO::geterror()));
  Image image = decode(*input, name);
  input->close();
  return image;
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

void encode(const std::filesystem::path& temporary, const std::filesystem::path& target,
            const Image& image, PixelFormat format) {
  const std::string where = "cannot write " + target.string() + ": ";
  auto output = OIIO::ImageOutput::create(temporary.string());
  if (!output) throw IoError(where + oneLine(OIIO::geterror()));
  if (!output->open(temporary.string(), outputSpec(image, typeOf(format))))
    throw IoError(where + oneLine(output->geterror()));
  if (!writeScanlines(*output, image, typeOf(format))) {
    const std::string message = oneLine(output->geterror());
    output->close();
    throw IoError(where + message);
  }
  if (!output->close()) throw IoError(where + oneLine(output->geterror()));
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
  if (content != FileKind::Unknown) return decodeBytes(bytes, content, name);

  // Another extension: let OpenImageIO try its other readers (Targa, Radiance HDR, ...).
  const OIIO::ImageSpec config = readerConfig();
  auto input = OIIO::ImageInput::open(name, &config);
  if (!input)
    throw InvalidInputError("cannot read " + name + ": " + oneLine(OIIO::geterror()) +
                            " (texgrad reads PNG, JPEG, OpenEXR and TIFF)");
  Image image = decode(*input, name);
  input->close();
  return image;
}

std::pair<int, int> readImageSize(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw IoError("cannot open " + name + ": No such file");
  const OIIO::ImageSpec config = readerConfig();
  auto input = OIIO::ImageInput::open(name, &config);
  if (!input) throw InvalidInputError("cannot read " + name + ": " + oneLine(OIIO::geterror()));
  const std::pair<int, int> size{input->spec().width, input->spec().height};
  input->close();
  return size;
}

Image readImageFromMemory(const std::vector<unsigned char>& bytes, const std::string& name) {
  const FileKind kind = kindOfContent(bytes);
  if (kind == FileKind::Unknown)
    throw InvalidInputError(name +
                            " is not a PNG, JPEG, OpenEXR or TIFF image (content looks like " +
                            describeContent(bytes) + ")");
  return decodeBytes(bytes, kind, name);
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
    encode(temporary, path, image, stored);
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

OIIO::ImageSpec outputSpec(const Image& image, OIIO::TypeDesc type) {
  OIIO::ImageSpec spec(image.width, image.height, image.channels, type);
  static const std::array<std::vector<std::string>, kMaxChannels> names{
      {{"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}}};
  spec.channelnames = names[static_cast<size_t>(image.channels - 1)];
  spec.alpha_channel = (image.channels == 2 || image.channels == 4) ? image.channels - 1 : -1;
  spec.attribute("oiio:UnassociatedAlpha", 1);
  return spec;
}

// OpenImageIO messages may span lines; texgrad errors are one line.
std::string oneLine(std::string message) {
  for (char& c : message)
    if (c == '\n' || c == '\r') c = ' ';
  while (!message.empty() && message.back() == ' ') message.pop_back();
  return message.empty() ? std::string("unknown OpenImageIO error") : message;
}

namespace {

/// Rows per strip of writeScanlines: 64 rows of a 16384-wide RGBA float image are 16 MB.
constexpr int kStripRows = 64;

/// Writes the file rows [0, height) of `image` as samples of type T, a strip at a time.
template <typename T>
bool writeStrips(OIIO::ImageOutput& output, const Image& image, OIIO::TypeDesc type) {
  const size_t row = static_cast<size_t>(image.width) * static_cast<size_t>(image.channels);
  std::vector<T> strip(row * static_cast<size_t>(std::min(kStripRows, image.height)));
  for (int first = 0; first < image.height; first += kStripRows) {
    const int end = std::min(first + kStripRows, image.height);
    for (int y = first; y < end; ++y) {
      // File row y (top first) is texel row height - 1 - y (texel rows go upward).
      const float* from = image.pixels.data() + static_cast<size_t>(image.height - 1 - y) * row;
      T* to = strip.data() + static_cast<size_t>(y - first) * row;
      for (size_t k = 0; k < row; ++k) {
        if constexpr (std::is_integral_v<T>) {
          constexpr float levels = static_cast<float>(std::numeric_limits<T>::max());
          const float clamped = std::isnan(from[k]) ? 0.0f : std::clamp(from[k], 0.0f, 1.0f);
          to[k] = static_cast<T>(std::lround(clamped * levels));
        } else {
          to[k] = from[k];
        }
      }
    }
    if (!output.write_scanlines(first, end, 0, type, strip.data())) return false;
  }
  return true;
}

}  // namespace

bool writeScanlines(OIIO::ImageOutput& output, const Image& image, OIIO::TypeDesc type) {
  if (type == OIIO::TypeDesc::UINT8) return writeStrips<uint8_t>(output, image, type);
  if (type == OIIO::TypeDesc::UINT16) return writeStrips<uint16_t>(output, image, type);
  return writeStrips<float>(output, image, OIIO::TypeDesc::FLOAT);  // OpenImageIO converts
}

}  // namespace texgrad
