#include "worker/io/image_codec.h"

#include <png.h>
// jpeglib.h needs size_t and FILE declared before it.
#include <jerror.h>
#include <jpeglib.h>
#include <cstdio>

#include <csetjmp>
#include <cstring>

#include "worker/io/io_error.h"

namespace keel::io {
namespace {

// Both libraries report errors by longjmp. The functions that setjmp hold no object with a
// destructor between setjmp and a possible longjmp: results go to the caller's objects through
// pointers, and the caller turns a failure into an exception.
struct CodecError {
  char message[JMSG_LENGTH_MAX > 200 ? JMSG_LENGTH_MAX : 200] = {0};
};

// --- PNG ---

struct PngInput {
  const uint8_t* data;
  size_t size;
  size_t position;
};

struct PngContext {
  std::jmp_buf jump;
  CodecError error;
};

void png_fail(png_structp png, png_const_charp message) {
  auto* context = static_cast<PngContext*>(png_get_error_ptr(png));
  std::snprintf(context->error.message, sizeof context->error.message, "%s", message);
  std::longjmp(context->jump, 1);
}

void png_ignore_warning(png_structp, png_const_charp) {}

void png_read_memory(png_structp png, png_bytep out, png_size_t count) {
  auto* in = static_cast<PngInput*>(png_get_io_ptr(png));
  if (count > in->size - in->position) png_error(png, "truncated PNG (data ends inside a chunk)");
  std::memcpy(out, in->data + in->position, count);
  in->position += count;
}

// Returns false with context->error set on failure. `rows` receives one pointer per row into
// image->pixels once the size is known.
bool png_decode_into(PngInput* input, DecodedImage* image, std::vector<png_bytep>* rows,
                     PngContext* context) {
  png_structp png =
      png_create_read_struct(PNG_LIBPNG_VER_STRING, context, png_fail, png_ignore_warning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(context->jump)) {
    png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
    return false;
  }
  png_set_read_fn(png, input, png_read_memory);
  png_read_info(png, info);
  const int colour = png_get_color_type(png, info);
  const int depth = png_get_bit_depth(png, info);
  if (colour == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (colour == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (colour & PNG_COLOR_MASK_ALPHA) png_set_strip_alpha(png);
  if (depth == 16) png_set_swap(png);  // PNG stores big-endian samples; Keel's are native
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  image->width = static_cast<int>(png_get_image_width(png, info));
  image->height = static_cast<int>(png_get_image_height(png, info));
  image->channels = png_get_channels(png, info);
  image->bit_depth = png_get_bit_depth(png, info);
  const size_t row_bytes = png_get_rowbytes(png, info);
  image->pixels.resize(row_bytes * static_cast<size_t>(image->height));
  rows->resize(static_cast<size_t>(image->height));
  for (size_t r = 0; r < rows->size(); ++r) (*rows)[r] = image->pixels.data() + r * row_bytes;
  png_read_image(png, rows->data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

struct PngOutput {
  std::string* bytes;
};

void png_write_memory(png_structp png, png_bytep data, png_size_t count) {
  static_cast<PngOutput*>(png_get_io_ptr(png))->bytes->append(reinterpret_cast<char*>(data), count);
}

void png_flush_nothing(png_structp) {}

bool png_encode_into(const uint8_t* pixels, int width, int height, int channels, PngOutput* output,
                     std::vector<png_bytep>* rows, PngContext* context) {
  png_structp png =
      png_create_write_struct(PNG_LIBPNG_VER_STRING, context, png_fail, png_ignore_warning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(context->jump)) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    return false;
  }
  png_set_write_fn(png, output, png_write_memory, png_flush_nothing);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8,
               channels == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  const size_t row_bytes = static_cast<size_t>(width) * channels;
  rows->resize(static_cast<size_t>(height));
  for (size_t r = 0; r < rows->size(); ++r)
    (*rows)[r] = const_cast<png_bytep>(pixels + r * row_bytes);
  png_write_image(png, rows->data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

// --- JPEG ---

struct JpegError {
  jpeg_error_mgr manager;  // first: libjpeg passes it as the error manager
  std::jmp_buf jump;
  CodecError error;
};

void jpeg_fail(j_common_ptr cinfo) {
  auto* error = reinterpret_cast<JpegError*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, error->error.message);
  std::longjmp(error->jump, 1);
}

// libjpeg warns and fills the rest of the image with grey when the data ends early; a camera
// image cut short is corrupt data, not an image: the warning is an error here.
void jpeg_message(j_common_ptr cinfo, int level) {
  if (level < 0 && cinfo->err->msg_code == JWRN_JPEG_EOF) jpeg_fail(cinfo);
}

bool jpeg_decode_into(const uint8_t* data, size_t size, DecodedImage* image, JpegError* error) {
  jpeg_decompress_struct cinfo;
  cinfo.err = jpeg_std_error(&error->manager);
  error->manager.error_exit = jpeg_fail;
  error->manager.emit_message = jpeg_message;
  if (setjmp(error->jump)) {
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, data, static_cast<unsigned long>(size));
  jpeg_read_header(&cinfo, TRUE);
  if (cinfo.jpeg_color_space == JCS_CMYK || cinfo.jpeg_color_space == JCS_YCCK) {
    std::snprintf(error->error.message, sizeof error->error.message,
                  "CMYK JPEG (camera images are gray or colour)");
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  cinfo.out_color_space = cinfo.num_components == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_start_decompress(&cinfo);
  image->width = static_cast<int>(cinfo.output_width);
  image->height = static_cast<int>(cinfo.output_height);
  image->channels = cinfo.output_components;
  image->bit_depth = 8;
  const size_t row_bytes = static_cast<size_t>(image->width) * image->channels;
  image->pixels.resize(row_bytes * static_cast<size_t>(image->height));
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = image->pixels.data() + cinfo.output_scanline * row_bytes;
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  return true;
}

}  // namespace

DecodedImage decode_png(const uint8_t* data, size_t size, const std::string& source) {
  DecodedImage image;
  std::vector<png_bytep> rows;
  PngInput input{data, size, 0};
  PngContext context;
  if (!png_decode_into(&input, &image, &rows, &context))
    throw IoError(source + ": cannot decode PNG: " + context.error.message);
  return image;
}

DecodedImage decode_jpeg(const uint8_t* data, size_t size, const std::string& source) {
  DecodedImage image;
  JpegError error;
  if (!jpeg_decode_into(data, size, &image, &error))
    throw IoError(source + ": cannot decode JPEG: " + error.error.message);
  return image;
}

std::string encode_png(const uint8_t* pixels, int width, int height, int channels) {
  std::string bytes;
  PngOutput output{&bytes};
  std::vector<png_bytep> rows;
  PngContext context;
  if (!png_encode_into(pixels, width, height, channels, &output, &rows, &context))
    throw IoError(std::string("cannot encode PNG: ") + context.error.message);
  return bytes;
}

}  // namespace keel::io
