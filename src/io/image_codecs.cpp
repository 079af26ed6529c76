// What the image codecs share: the limits on declared images, one-line messages, and the
// checked output file of the stdio-based writers.
#include "image_codecs.h"

#include "texgrad/core/error.h"

namespace texgrad::codec {
namespace {

/// Largest image accepted (2^30 texels, e.g. 32768 x 32768): beyond it the float copy alone
/// needs more than 4 GB per channel, which is a mistake rather than a texture.
constexpr int64_t kMaxTexels = int64_t{1} << 30;
/// Channels texgrad processes: grey, grey + alpha, RGB, RGBA.
constexpr int kMaxChannels = 4;

}  // namespace

void checkDeclaredImage(int width, int height, int channels, const std::string& name) {
  if (width <= 0 || height <= 0)
    throw InvalidInputError(name + " declares an empty image (" + std::to_string(width) + " x " +
                            std::to_string(height) + "); re-export the texture");
  if (channels < 1 || channels > kMaxChannels)
    throw UnsupportedError(name + " has " + std::to_string(channels) +
                           " channels; texgrad handles 1 to 4 (grey, grey+alpha, RGB, RGBA)");
  if (static_cast<int64_t>(width) * height > kMaxTexels)
    throw UnsupportedError(name + " is " + std::to_string(width) + " x " +
                           std::to_string(height) + " texels; texgrad handles at most " +
                           std::to_string(kMaxTexels) + " texels");
}

std::string oneLine(std::string message) {
  for (char& c : message)
    if (c == '\n' || c == '\r') c = ' ';
  while (!message.empty() && message.back() == ' ') message.pop_back();
  return message.empty() ? std::string("unknown error") : message;
}

OutputFile::OutputFile(const std::filesystem::path& path, const std::string& where)
    : file_(std::fopen(path.c_str(), "wb")), where_(where) {
  if (!file_) throw IoError(where_ + "cannot create the file (permission denied or disk full)");
}

OutputFile::~OutputFile() {
  if (file_) std::fclose(file_);  // only after an error: the partial file is discarded anyway
}

void OutputFile::close() {
  const bool written = std::fflush(file_) == 0 && !std::ferror(file_);
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!written || !closed) throw IoError(where_ + "writing failed (disk full?)");
}

}  // namespace texgrad::codec
