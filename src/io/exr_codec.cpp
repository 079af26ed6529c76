// OpenEXR through its C++ library. Rows go through a strip of file rows (top first), which is
// then copied to the texel rows (bottom first): OpenEXR's strides are unsigned, so a frame buffer
// cannot walk the texel rows backwards.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStdIO.h>
#include <Imath/half.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>

#include "image_codecs.h"
#include "texgrad/core/error.h"

namespace texgrad::codec {
namespace {

/// Rows per strip: 64 rows of a 16384-wide RGBA image are 16 MB of floats.
constexpr int kStripRows = 64;

/// An OpenEXR input stream over bytes in memory.
class MemoryStream : public Imf::IStream {
 public:
  MemoryStream(Bytes bytes, const std::string& name) : Imf::IStream(name.c_str()), bytes_(bytes) {}

  bool read(char c[], int n) override {
    if (n < 0 || static_cast<size_t>(n) > bytes_.size() - position_)
      throw Iex::InputExc("unexpected end of file");
    std::memcpy(c, bytes_.data() + position_, static_cast<size_t>(n));
    position_ += static_cast<size_t>(n);
    return position_ < bytes_.size();
  }
  uint64_t tellg() override { return position_; }
  void seekg(uint64_t position) override {
    if (position > bytes_.size()) throw Iex::InputExc("seek past the end of file");
    position_ = position;
  }

 private:
  Bytes bytes_;
  size_t position_ = 0;
};

/// The file's channels in the order texgrad holds them: R, G, B or Y first, others by name
/// (OpenEXR lists them alphabetically), alpha last.
std::vector<std::string> orderedChannels(const Imf::ChannelList& list) {
  std::vector<std::string> names;
  for (auto it = list.begin(); it != list.end(); ++it) names.emplace_back(it.name());
  auto rank = [](const std::string& name) {
    static constexpr std::array<const char*, 4> first = {"R", "G", "B", "Y"};
    for (size_t k = 0; k < first.size(); ++k)
      if (name == first[k]) return static_cast<int>(k);
    return name == "A" ? 5 : 4;
  };
  std::stable_sort(names.begin(), names.end(),
                   [&](const std::string& a, const std::string& b) { return rank(a) < rank(b); });
  return names;
}

/// Reads a null-terminated header string of at most 255 characters (OpenEXR's long-name limit).
std::string readName(Imf::IStream& stream) {
  std::string name;
  char c = 0;
  while (stream.read(&c, 1), c != '\0') {
    if (name.size() == 255) throw Iex::InputExc("header name too long");
    name.push_back(c);
  }
  return name;
}

/// Checks that every attribute of the first header fits in the file's `size` bytes before
/// OpenEXR reads it: OpenEXR allocates (and fills) what an attribute declares, so a few hundred
/// corrupt bytes could otherwise cost gigabytes. The stream is left just past the header.
void checkAttributeSizes(Imf::IStream& stream, uint64_t size) {
  while (!readName(stream).empty()) {
    readName(stream);  // the attribute's type
    std::array<char, 4> length{};
    stream.read(length.data(), 4);
    int32_t bytes = 0;
    std::memcpy(&bytes, length.data(), 4);  // little-endian in the file, as on texgrad's hosts
    if (bytes < 0 || static_cast<uint64_t>(bytes) > size - stream.tellg())
      throw Iex::InputExc("a header attribute runs past the end of the file");
    stream.seekg(stream.tellg() + static_cast<uint64_t>(bytes));
  }
}

/// Reads the header of the first part of a file of `size` bytes (the stream is then past it);
/// throws OpenEXR's exceptions.
Imf::Header readHeader(Imf::IStream& stream, uint64_t size) {
  std::array<char, 8> start{};  // magic number and version (OpenEXR file layout)
  stream.read(start.data(), static_cast<int>(start.size()));
  int32_t magic = 0, version = 0;
  std::memcpy(&magic, start.data(), 4);  // little-endian in the file, as on texgrad's hosts
  std::memcpy(&version, start.data() + 4, 4);
  if (magic != 20000630) throw Iex::InputExc("not an OpenEXR file");
  checkAttributeSizes(stream, size);
  stream.seekg(start.size());
  Imf::Header header;
  int readVersion = version;
  header.readFrom(stream, readVersion);
  return header;
}

/// Width and height of a data window, checked to fit an int.
Size windowSize(const Imath::Box2i& window, const std::string& name) {
  const int64_t width = int64_t{window.max.x} - window.min.x + 1,
                height = int64_t{window.max.y} - window.min.y + 1;
  if (width <= 0 || height <= 0 || width > INT32_MAX || height > INT32_MAX)
    throw InvalidInputError(name + " declares an impossible data window (" +
                            std::to_string(width) + " x " + std::to_string(height) + ")");
  return {static_cast<int>(width), static_cast<int>(height)};
}

/// Checks what the header describes and returns the channels to read, in texgrad's order.
std::vector<std::string> checkedChannels(const Imf::Header& header, const std::string& name) {
  if (header.dataWindow() != header.displayWindow())
    throw UnsupportedError(name +
                           " has a data window different from its display window; "
                           "crop it to the full image first (oiiotool IN --croptofull -o OUT)");
  const auto [width, height] = windowSize(header.dataWindow(), name);
  const std::vector<std::string> channels = orderedChannels(header.channels());
  checkDeclaredImage(width, height, static_cast<int>(channels.size()), name);
  for (auto it = header.channels().begin(); it != header.channels().end(); ++it)
    if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
      throw UnsupportedError(name + " has subsampled channels (" + it.name() +
                             "); convert it to full-resolution channels first");
  return channels;
}

/// Half if every channel is half, float otherwise (the format a rewrite keeps).
PixelFormat formatOf(const Imf::ChannelList& list) {
  for (auto it = list.begin(); it != list.end(); ++it)
    if (it.channel().type != Imf::HALF) return PixelFormat::Float;
  return PixelFormat::Half;
}

/// Decodes the pixels of `file` (whose channels are `channels`) into `image`, a strip at a time.
void readStrips(Imf::InputFile& file, const std::vector<std::string>& channels, Image& image) {
  const Imath::Box2i& window = file.header().dataWindow();
  const size_t row = static_cast<size_t>(image.width) * static_cast<size_t>(image.channels);
  std::vector<float> strip(row * static_cast<size_t>(std::min(kStripRows, image.height)));
  for (int first = 0; first < image.height; first += kStripRows) {
    const int rows = std::min(kStripRows, image.height - first);
    Imf::FrameBuffer buffer;
    for (size_t c = 0; c < channels.size(); ++c)
      buffer.insert(channels[c],
                    Imf::Slice::Make(Imf::FLOAT, strip.data() + c,
                                     Imath::V2i(window.min.x, window.min.y + first), image.width,
                                     rows, sizeof(float) * channels.size(), sizeof(float) * row));
    file.setFrameBuffer(buffer);
    file.readPixels(window.min.y + first, window.min.y + first + rows - 1);
    for (int y = 0; y < rows; ++y)
      std::copy_n(strip.data() + static_cast<size_t>(y) * row, row, fileRow(image, first + y));
  }
}

/// Writes the rows of `image` to `out` as samples of type T (float, or half: OpenEXR does not
/// convert between them on output), a strip at a time.
template <typename T>
void writeStrips(Imf::OutputFile& out, const Image& image, const std::vector<std::string>& channels) {
  constexpr Imf::PixelType type = std::is_same_v<T, float> ? Imf::FLOAT : Imf::HALF;
  const size_t row = static_cast<size_t>(image.width) * static_cast<size_t>(image.channels);
  std::vector<T> strip(row * static_cast<size_t>(std::min(kStripRows, image.height)));
  for (int first = 0; first < image.height; first += kStripRows) {
    const int rows = std::min(kStripRows, image.height - first);
    for (int y = 0; y < rows; ++y) {
      const float* from = fileRow(image, first + y);
      std::copy(from, from + row, strip.data() + static_cast<size_t>(y) * row);  // half rounds
    }
    Imf::FrameBuffer buffer;
    for (size_t c = 0; c < channels.size(); ++c)
      buffer.insert(channels[c],
                    Imf::Slice::Make(type, strip.data() + c, Imath::V2i(0, first), image.width,
                                     rows, sizeof(T) * channels.size(), sizeof(T) * row));
    out.setFrameBuffer(buffer);
    out.writePixels(rows);
  }
}

std::string oneLineOf(const std::exception& e) { return oneLine(e.what()); }

}  // namespace

Image decodeExr(Bytes bytes, const std::string& name) {
  try {
    MemoryStream stream(bytes, name);
    // The header is checked before OpenEXR sizes its buffers from it.
    const std::vector<std::string> channels =
        checkedChannels(readHeader(stream, bytes.size()), name);
    stream.seekg(0);
    Imf::InputFile file(stream, 1);
    if (!file.isComplete())
      throw InvalidInputError(name + " is truncated (some of its scanlines or tiles are missing)");
    const auto [width, height] = windowSize(file.header().dataWindow(), name);
    Image image(width, height, static_cast<int>(channels.size()),
                formatOf(file.header().channels()));
    readStrips(file, channels, image);
    return image;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw InvalidInputError(name + " is truncated or corrupt: " + oneLineOf(e));
  }
}

Size exrSize(const std::filesystem::path& path) {
  try {
    Imf::StdIFStream stream(path.c_str());
    return windowSize(readHeader(stream, std::filesystem::file_size(path)).dataWindow(),
                      path.string());
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw InvalidInputError("cannot read the header of " + path.string() + ": " + oneLineOf(e));
  }
}

void writeExr(const std::filesystem::path& file, const Image& image, bool half,
              const std::string& where) {
  static const std::array<std::vector<std::string>, 4> names{
      {{"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}}};
  const std::vector<std::string>& channels = names[static_cast<size_t>(image.channels - 1)];
  try {
    Imf::Header header(image.width, image.height);  // ZIP compression, increasing rows
    for (const std::string& channel : channels)
      header.channels().insert(channel, Imf::Channel(half ? Imf::HALF : Imf::FLOAT));
    // OpenEXR closes a file it opened itself in its destructor, where a failed write (a full
    // disk) goes unnoticed: the stream is ours, and checked once OpenEXR is done with it.
    std::ofstream bytes(file, std::ios::binary);
    if (!bytes) throw IoError(where + "cannot create the file");
    {
      Imf::StdOFStream stream(bytes, file.c_str());
      Imf::OutputFile out(stream, header, 1);
      if (half)
        writeStrips<Imath::half>(out, image, channels);
      else
        writeStrips<float>(out, image, channels);
    }
    bytes.close();
    if (!bytes) throw IoError(where + "writing failed (disk full?)");
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw IoError(where + oneLineOf(e));
  }
}

}  // namespace texgrad::codec
