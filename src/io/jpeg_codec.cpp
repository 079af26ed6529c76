// JPEG through libjpeg-turbo. libjpeg reports an error through error_exit, which here jumps back
// (longjmp) to the function that called it: those functions hold no object with a destructor
// (buffers and the image belong to their caller), so no destructor is ever skipped.
#include <array>
#include <csetjmp>
#include <cstdio>
#include <memory>
#include <new>

// jpeglib.h needs FILE and size_t declared first.
#include <jpeglib.h>
// After jpeglib.h: the message codes (JERR_*).
#include <jerror.h>

#include "image_codecs.h"
#include "texgrad/core/error.h"

namespace texgrad::codec {
namespace {

/// libjpeg's error manager with the jump point and the first message (a fixed buffer, with its
/// code and first number).
struct JpegErrors {
  jpeg_error_mgr manager{};
  std::jmp_buf jump{};
  std::array<char, JMSG_LENGTH_MAX> first{};
  int firstCode = 0;
  int firstNumber = 0;
  bool warned = false;
};

void keepMessage(j_common_ptr info) {
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  if (errors->first[0] != '\0') return;
  info->err->format_message(info, errors->first.data());
  errors->firstCode = info->err->msg_code;
  errors->firstNumber = info->err->msg_parm.i[0];
}

/// Throws UnsupportedError if a header could not be read because the file's samples are not 8
/// bits (12-bit JPEGs, which this libjpeg build does not decode).
void refuseOtherPrecisions(const std::string& name, const JpegErrors& errors) {
  if (errors.firstCode == JERR_BAD_PRECISION)
    throw UnsupportedError(name + " is a " + std::to_string(errors.firstNumber) +
                           "-bit JPEG; texgrad reads 8-bit JPEGs: convert it to a 16-bit PNG or "
                           "TIFF first (e.g. oiiotool " + name + " -d uint16 -o OUT.png)");
}

[[noreturn]] void onJpegError(j_common_ptr info) {
  keepMessage(info);
  std::longjmp(reinterpret_cast<JpegErrors*>(info->err)->jump, 1);
}

/// Level -1 is a warning (a premature end, corrupt data, which libjpeg fills with grey): kept,
/// so that the image is refused; trace messages (levels >= 0) are dropped. Nothing is printed.
void onJpegMessage(j_common_ptr info, int level) {
  if (level >= 0) return;
  keepMessage(info);
  reinterpret_cast<JpegErrors*>(info->err)->warned = true;
}

void installErrors(JpegErrors& errors) {
  jpeg_std_error(&errors.manager);
  errors.manager.error_exit = onJpegError;
  errors.manager.emit_message = onJpegMessage;
  errors.manager.output_message = [](j_common_ptr) {};
}

/// jpeg_create_decompress or jpeg_create_compress on `info` under the jump point of `errors`;
/// false if it failed, which it does only when its memory manager gets no memory (a version
/// mismatch, its other failure, the build rules out).
template <typename Info, typename Create>
bool created(Info* info, JpegErrors* errors, Create create) {
  if (setjmp(errors->jump)) return false;
  create(info);
  return true;
}

/// libjpeg's decompressor for the lifetime of one decode.
struct JpegReader {
  jpeg_decompress_struct info{};
  JpegErrors errors;

  JpegReader() {
    installErrors(errors);
    info.err = &errors.manager;
    if (!created(&info, &errors, [](jpeg_decompress_struct* i) { jpeg_create_decompress(i); }))
      throw std::bad_alloc();
  }
  ~JpegReader() { jpeg_destroy_decompress(&info); }
  JpegReader(const JpegReader&) = delete;
  JpegReader& operator=(const JpegReader&) = delete;
};

/// Reads the header from `bytes`, or from `file` if given; false on an error.
bool readHeader(JpegReader* reader, Bytes bytes, std::FILE* file) {
  if (setjmp(reader->errors.jump)) return false;
  jpeg_decompress_struct& info = reader->info;
  if (file)
    jpeg_stdio_src(&info, file);
  else
    jpeg_mem_src(&info, bytes.data(), static_cast<unsigned long>(bytes.size()));
  jpeg_read_header(&info, TRUE);
  return true;
}

bool isCmyk(const jpeg_decompress_struct& info) {
  return info.jpeg_color_space == JCS_CMYK || info.jpeg_color_space == JCS_YCCK;
}

/// Starts decompression into grey or RGB samples (not CMYK); false on an error. A progressive
/// file is decoded whole here, into coefficient buffers sized by its header: call it only once
/// that size is checked.
bool startDecompress(JpegReader* reader) {
  if (setjmp(reader->errors.jump)) return false;
  jpeg_decompress_struct& info = reader->info;
  info.out_color_space = info.jpeg_color_space == JCS_GRAYSCALE ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_start_decompress(&info);
  return true;
}

/// Decodes every scanline into `image` through `row`; false on an error.
bool readScanlines(JpegReader* reader, unsigned char* row, Image* image) {
  if (setjmp(reader->errors.jump)) return false;
  jpeg_decompress_struct& info = reader->info;
  while (info.output_scanline < info.output_height) {
    const int y = static_cast<int>(info.output_scanline);
    JSAMPROW rows[1] = {row};
    jpeg_read_scanlines(&info, rows, 1);
    levelsToRow(row, *image, y);
  }
  jpeg_finish_decompress(&info);
  return true;
}

std::string corrupt(const std::string& name, const JpegErrors& errors) {
  return name + " is truncated or corrupt: " + oneLine(errors.first.data());
}

/// libjpeg's compressor for the lifetime of one encode.
struct JpegWriter {
  jpeg_compress_struct info{};
  JpegErrors errors;

  JpegWriter() {
    installErrors(errors);
    info.err = &errors.manager;
    if (!created(&info, &errors, [](jpeg_compress_struct* i) { jpeg_create_compress(i); }))
      throw std::bad_alloc();
  }
  ~JpegWriter() { jpeg_destroy_compress(&info); }
  JpegWriter(const JpegWriter&) = delete;
  JpegWriter& operator=(const JpegWriter&) = delete;
};

/// Quality of written JPEGs: visually lossless, as texture pipelines expect.
constexpr int kQuality = 98;

/// Compresses `image` (1 or 3 channels) into `file` through `row`; false on an error.
bool writeScanlines(JpegWriter* writer, const Image& image, std::FILE* file, unsigned char* row) {
  if (setjmp(writer->errors.jump)) return false;
  jpeg_compress_struct& info = writer->info;
  jpeg_stdio_dest(&info, file);
  info.image_width = static_cast<JDIMENSION>(image.width);
  info.image_height = static_cast<JDIMENSION>(image.height);
  info.input_components = image.channels;
  info.in_color_space = image.channels == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_set_defaults(&info);
  jpeg_set_quality(&info, kQuality, TRUE);
  jpeg_start_compress(&info, TRUE);
  for (int y = 0; y < image.height; ++y) {
    quantiseRow(image, y, row);
    JSAMPROW rows[1] = {row};
    jpeg_write_scanlines(&info, rows, 1);
  }
  jpeg_finish_compress(&info);
  return true;
}

}  // namespace

Image decodeJpeg(Bytes bytes, const std::string& name) {
  JpegReader reader;
  if (!readHeader(&reader, bytes, nullptr) || reader.errors.warned) {
    refuseOtherPrecisions(name, reader.errors);
    throw InvalidInputError(corrupt(name, reader.errors));
  }
  const jpeg_decompress_struct& info = reader.info;
  if (isCmyk(info))
    throw UnsupportedError(name + " is a CMYK JPEG; convert it to RGB first (e.g. oiiotool " +
                           name + " --ch R,G,B -o OUT.png)");
  checkDeclaredImage(static_cast<int>(info.image_width), static_cast<int>(info.image_height),
                     info.jpeg_color_space == JCS_GRAYSCALE ? 1 : 3, name);
  if (!startDecompress(&reader) || reader.errors.warned)
    throw InvalidInputError(corrupt(name, reader.errors));
  Image image(static_cast<int>(info.output_width), static_cast<int>(info.output_height),
              info.output_components, PixelFormat::UInt8);
  std::vector<unsigned char> row(static_cast<size_t>(image.width) *
                                 static_cast<size_t>(image.channels));
  if (!readScanlines(&reader, row.data(), &image) || reader.errors.warned)
    throw InvalidInputError(corrupt(name, reader.errors));
  return image;
}

Size jpegSize(const std::filesystem::path& path) {
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> in(std::fopen(path.c_str(), "rb"),
                                                           std::fclose);
  if (!in) throw IoError("cannot open " + path.string() + ": permission denied or unreadable");
  JpegReader reader;
  if (!readHeader(&reader, {}, in.get())) {
    refuseOtherPrecisions(path.string(), reader.errors);
    throw InvalidInputError("cannot read the header of " + path.string() + ": " +
                            oneLine(reader.errors.first.data()));
  }
  return {static_cast<int>(reader.info.image_width), static_cast<int>(reader.info.image_height)};
}

void writeJpeg(const std::filesystem::path& file, const Image& image, const std::string& where) {
  OutputFile out(file, where);
  JpegWriter writer;
  std::vector<unsigned char> row(static_cast<size_t>(image.width) *
                                 static_cast<size_t>(image.channels));
  if (!writeScanlines(&writer, image, out.get(), row.data()))
    throw IoError(where + oneLine(writer.errors.first.data()));
  out.close();
}

}  // namespace texgrad::codec
