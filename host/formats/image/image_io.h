// Output files (CONTRACT "Outputs"): PNG, PFM, OpenEXR, the item buffer as .npy, text.
// Every writer builds the whole file in memory, writes it to a temporary file
// in the destination folder and renames it into place only after a complete,
// checked write, so no partial output file is ever left behind.
// Write failures throw InputError("OUT: cannot write (reason)").
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace opsila {

// IEC 61966-2-1 sRGB transfer function of a linear value clamped to [0,1]
// (NaN counts as 0).
float srgb_encode(float linear);
// srgb_encode, scaled to 0..255 and rounded to nearest.
std::uint8_t to_srgb8(float linear);
std::vector<std::uint8_t> to_srgb8(const std::vector<float>& linear);

// Throws InputError("PATH: cannot write (reason)") unless PATH could be
// created: its folder exists and is writable, and PATH is not a folder.
// Lets the command line fail before any rendering is done.
void check_output_path(const std::string& path);
// Where an output named `path` lands: a symbolic link's target, followed to
// its end (as a shell's redirection or cp writes through a link), else
// `path` itself. The file is replaced there, and the link stays.
std::string output_destination(const std::string& path);
// Whether `folder` is append-only or immutable (chattr +a, +i): files can
// be added to it, or nothing at all, but none renamed or removed, so an
// output written beside its name could not be put in place or taken away.
bool folder_keeps_its_names(const std::string& folder);

// Writes all `size` bytes to `fd`: 0, or the errno of the write that
// failed. The file-size limit (ulimit -f) fails it with EFBIG as a full
// disk would, instead of SIGXFSZ killing the process with its temporary
// file left behind (the signal is ignored from the first call on).
int write_all(int fd, const void* data, std::size_t size);

// Atomic write of `size` bytes (temporary file + rename).
void write_file_atomic(const std::string& path, const void* data, std::size_t size);
void write_text_file(const std::string& path, const std::string& text);

// rgb: linear floats, 3 per pixel, row 0 = top. The encoders return the
// whole file (for OutputFiles); the writers write it atomically.
std::string encode_png(int width, int height, const std::vector<float>& rgb);
// Every value must be finite (std::logic_error otherwise: the renderers
// never produce NaN or infinity, and a PFM must not hold one).
std::string encode_pfm(int width, int height, const std::vector<float>& rgb);
// OpenEXR (host/formats/image/image_exr.cpp): linear RGB channels R, G, B, 32-bit
// float, or 16-bit half when `half` (a value beyond half's range is stored
// as its largest, 65504), lossless ZIP compression, row 0 = top. Every
// value must be finite, as for PFM. Throws InputError when this build has
// no OpenEXR (exr_available() says so before any rendering).
bool exr_available();
std::string encode_exr(int width, int height, const std::vector<float>& rgb, bool half);
void write_png(const std::string& path, int width, int height, const std::vector<float>& rgb);
void write_pfm(const std::string& path, int width, int height, const std::vector<float>& rgb);

struct FloatImage {
  int width = 0, height = 0;
  std::vector<float> rgb;  // 3 per pixel, row 0 = top
};
// Reads PF (RGB) and Pf (grey, expanded to RGB), either byte order.
// Throws InputError naming the file on malformed input.
FloatImage read_pfm(const std::string& path);

// NumPy .npy v1.0, dtype '<i4', shape (H, W, 2); items: (object, facet) per pixel.
std::string encode_npy_item_buffer(int height, int width, const std::vector<std::int32_t>& items);
void write_npy_item_buffer(const std::string& path, int height, int width,
                           const std::vector<std::int32_t>& items);

struct ItemBufferFile {
  int height = 0, width = 0;
  std::vector<std::int32_t> items;  // 2 per pixel
};
// Reads what write_npy_item_buffer writes ('<i4', C order, shape (H, W, 2)).
ItemBufferFile read_npy_item_buffer(const std::string& path);

// Peak signal-to-noise ratio in dB of equally sized buffers: 10 log10(peak² / MSE).
// +infinity when identical. Throws std::invalid_argument on a size mismatch.
double psnr(const std::vector<float>& a, const std::vector<float>& b, double peak);

}  // namespace opsila
