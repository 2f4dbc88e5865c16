#include "formats/image/image_io.h"

#include <fcntl.h>
#include <linux/fs.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "core/input_file.h"
#include "scene/scene.h"
#include "core/util.h"

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#include <stb/stb_image_write.h>
#pragma GCC diagnostic pop

namespace opsila {

namespace {

[[noreturn]] void cannot_write(const std::string& path, const std::string& reason) {
  throw InputError(path + ": cannot write (" + reason + ")");
}

bool little_endian_host() {
  const std::uint32_t one = 1;
  unsigned char first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

void append_le32(std::string& out, const void* four_bytes) {
  unsigned char b[4];
  std::memcpy(b, four_bytes, 4);
  if (!little_endian_host()) {
    std::swap(b[0], b[3]);
    std::swap(b[1], b[2]);
  }
  out.append(reinterpret_cast<const char*>(b), 4);
}

// Reads 4 bytes stored in the given byte order into a host value.
template <typename T>
T read_4(const char* p, bool little) {
  static_assert(sizeof(T) == 4, "4-byte values only");
  unsigned char b[4];
  std::memcpy(b, p, 4);
  if (little != little_endian_host()) {
    std::swap(b[0], b[3]);
    std::swap(b[1], b[2]);
  }
  T value;
  std::memcpy(&value, b, 4);
  return value;
}

std::string read_whole_file(const std::string& path) { return read_input_file(path, kMaxInputFileBytes); }

void check_image_size(int width, int height, std::size_t have, std::size_t per_pixel) {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("image size must be positive");
  if (have != static_cast<std::size_t>(width) * height * per_pixel)
    throw std::invalid_argument("pixel buffer does not match the image size");
}

}  // namespace

// ------------------------------------------------------------------ sRGB

float srgb_encode(float linear) {
  if (!(linear > 0.0f)) return 0.0f;  // also NaN
  if (linear >= 1.0f) return 1.0f;
  if (linear <= 0.0031308f) return 12.92f * linear;
  return 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
}

std::uint8_t to_srgb8(float linear) {
  const float v = srgb_encode(linear) * 255.0f + 0.5f;
  return static_cast<std::uint8_t>(std::min(255.0f, std::max(0.0f, v)));
}

std::vector<std::uint8_t> to_srgb8(const std::vector<float>& linear) {
  std::vector<std::uint8_t> out(linear.size());
  for (std::size_t i = 0; i < linear.size(); ++i) out[i] = to_srgb8(linear[i]);
  return out;
}

// ------------------------------------------------------------- atomic write

void check_output_path(const std::string& path) {
  if (path.empty()) cannot_write("''", "empty path");
  if (path.back() == '/') cannot_write(path, "is a folder");
  struct stat st;
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) cannot_write(path, "is a folder");
  const std::string folder = folder_of(path);
  if (::stat(folder.c_str(), &st) != 0)
    cannot_write(path, "folder " + folder + ": " + std::strerror(errno));
  if (!S_ISDIR(st.st_mode)) cannot_write(path, folder + " is not a folder");
  if (::access(folder.c_str(), W_OK | X_OK) != 0)
    cannot_write(path, "folder " + folder + ": " + std::strerror(errno));
  if (folder_keeps_its_names(folder))
    cannot_write(path, "folder " + folder + " is append-only or immutable: an output is written beside its name, then "
                       "renamed, which such a folder refuses");
}

std::string output_destination(const std::string& path) {
  std::string at = path;
  for (int hops = 0; hops < 40; ++hops) {  // Linux's own limit on a path's links
    struct stat st;
    if (::lstat(at.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return at;
    std::error_code ec;
    const std::filesystem::path to = std::filesystem::read_symlink(at, ec);
    if (ec) cannot_write(path, "symbolic link " + at + ": " + ec.message());
    at = to.is_absolute() ? to.string() : (std::filesystem::path(at).parent_path() / to).string();
  }
  cannot_write(path, std::strerror(ELOOP));
}

bool folder_keeps_its_names(const std::string& folder) {
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return false;
  int flags = 0;  // where the file system keeps no such flags the ioctl fails: nothing to refuse
  const bool kept = ::ioctl(fd, FS_IOC_GETFLAGS, &flags) == 0 && (flags & (FS_APPEND_FL | FS_IMMUTABLE_FL)) != 0;
  ::close(fd);
  return kept;
}

int write_all(int fd, const void* data, std::size_t size) {
  // Set on every call: a library loaded meanwhile (LLVM, inside an OpenCL
  // driver) may have put a handler of its own there.
  ::signal(SIGXFSZ, SIG_IGN);
  const char* bytes = static_cast<const char*>(data);
  for (std::size_t done = 0; done < size;) {
    const ssize_t n = ::write(fd, bytes + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return errno;
    done += static_cast<std::size_t>(n);
  }
  return 0;
}

void write_file_atomic(const std::string& name, const void* data, std::size_t size) {
  const std::string path = output_destination(name);
  check_output_path(path);
  // The temporary file lives next to the target so that rename() is atomic;
  // open() with mode 0666 lets the umask decide the final permissions.
  static std::atomic<unsigned> counter{0};
  const std::string folder = folder_of(path);
  std::string temp;
  int fd = -1;
  for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
    temp = folder + "/." + name_of(path) + ".tmp-" + std::to_string(::getpid()) + "-" +
           std::to_string(counter++);
    fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0 && errno != EEXIST) cannot_write(path, std::strerror(errno));
  }
  if (fd < 0) cannot_write(path, "no free temporary file name");

  auto fail = [&](const std::string& reason) {
    if (fd >= 0) ::close(fd);
    ::unlink(temp.c_str());
    cannot_write(path, reason);
  };
  if (const int err = write_all(fd, data, size)) fail(std::strerror(err));
  if (::fsync(fd) != 0 && errno != EINVAL && errno != EROFS) fail(std::strerror(errno));
  const int closed = ::close(fd);
  fd = -1;
  if (closed != 0) fail(std::strerror(errno));
  if (::rename(temp.c_str(), path.c_str()) != 0) fail(std::strerror(errno));
}

void write_text_file(const std::string& path, const std::string& text) {
  write_file_atomic(path, text.data(), text.size());
}

// ------------------------------------------------------------------ PNG

std::string encode_png(int width, int height, const std::vector<float>& rgb) {
  check_image_size(width, height, rgb.size(), 3);
  const std::vector<std::uint8_t> pixels = to_srgb8(rgb);
  std::string encoded;
  auto append = [](void* context, void* bytes, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(bytes), size);
  };
  if (!stbi_write_png_to_func(append, &encoded, width, height, 3, pixels.data(), width * 3))
    throw std::runtime_error("PNG encoding failed");
  return encoded;
}

void write_png(const std::string& path, int width, int height, const std::vector<float>& rgb) {
  const std::string encoded = encode_png(width, height, rgb);
  write_file_atomic(path, encoded.data(), encoded.size());
}

// ------------------------------------------------------------------ PFM

std::string encode_pfm(int width, int height, const std::vector<float>& rgb) {
  check_image_size(width, height, rgb.size(), 3);
  for (float v : rgb)
    if (!std::isfinite(v)) throw std::logic_error("a pixel value is not finite; no PFM is written");
  // Scale -1 = little-endian; the format stores the bottom row first.
  std::string out = "PF\n" + std::to_string(width) + " " + std::to_string(height) + "\n-1.0\n";
  out.reserve(out.size() + rgb.size() * 4);
  for (int y = height - 1; y >= 0; --y) {
    const float* row = rgb.data() + static_cast<std::size_t>(y) * width * 3;
    for (int i = 0; i < width * 3; ++i) append_le32(out, &row[i]);
  }
  return out;
}

void write_pfm(const std::string& path, int width, int height, const std::vector<float>& rgb) {
  const std::string out = encode_pfm(width, height, rgb);
  write_file_atomic(path, out.data(), out.size());
}

FloatImage read_pfm(const std::string& path) {
  const std::string data = read_whole_file(path);
  // Header: three whitespace-separated tokens after the magic, then exactly
  // one whitespace character before the raster.
  std::size_t pos = 0;
  auto token = [&]() {
    while (pos < data.size() && std::isspace(static_cast<unsigned char>(data[pos]))) ++pos;
    const std::size_t start = pos;
    while (pos < data.size() && !std::isspace(static_cast<unsigned char>(data[pos]))) ++pos;
    return data.substr(start, pos - start);
  };
  const std::string magic = token();
  if (magic != "PF" && magic != "Pf") throw InputError(path + ": not a PFM file");
  const int channels = magic == "PF" ? 3 : 1;
  const std::string w = token(), h = token(), scale = token();
  if (pos >= data.size()) throw InputError(path + ": truncated PFM header");
  ++pos;  // the single whitespace after the scale
  FloatImage image;
  double scale_value = 0;
  try {
    std::size_t used_w, used_h, used_s;
    image.width = std::stoi(w, &used_w);
    image.height = std::stoi(h, &used_h);
    scale_value = std::stod(scale, &used_s);
    if (used_w != w.size() || used_h != h.size() || used_s != scale.size()) throw std::exception();
  } catch (...) {
    throw InputError(path + ": malformed PFM header");
  }
  if (image.width <= 0 || image.height <= 0 || scale_value == 0 || !std::isfinite(scale_value))
    throw InputError(path + ": malformed PFM header");
  const bool little = scale_value < 0;
  const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
  if (data.size() - pos != pixels * channels * 4)
    throw InputError(path + ": PFM raster size does not match " + w + "x" + h);
  image.rgb.resize(pixels * 3);
  for (int y = 0; y < image.height; ++y) {
    const int file_row = image.height - 1 - y;
    for (int x = 0; x < image.width; ++x) {
      const std::size_t src = pos + (static_cast<std::size_t>(file_row) * image.width + x) * channels * 4;
      const std::size_t dst = (static_cast<std::size_t>(y) * image.width + x) * 3;
      for (int c = 0; c < 3; ++c)
        image.rgb[dst + c] = read_4<float>(data.data() + src + (channels == 3 ? c : 0) * 4, little);
    }
  }
  return image;
}

// ------------------------------------------------------------------ NPY

std::string encode_npy_item_buffer(int height, int width, const std::vector<std::int32_t>& items) {
  check_image_size(width, height, items.size(), 2);
  std::string header = "{'descr': '<i4', 'fortran_order': False, 'shape': (" +
                       std::to_string(height) + ", " + std::to_string(width) + ", 2), }";
  // Magic (6) + version (2) + length (2) + header, padded with spaces so the
  // data starts on a 64-byte boundary, the header ending in '\n'.
  const std::size_t preamble = 10;
  const std::size_t unpadded = preamble + header.size() + 1;
  header.append((64 - unpadded % 64) % 64, ' ');
  header.push_back('\n');
  std::string out("\x93NUMPY\x01\x00", 8);
  out.push_back(static_cast<char>(header.size() & 0xff));
  out.push_back(static_cast<char>((header.size() >> 8) & 0xff));
  out += header;
  out.reserve(out.size() + items.size() * 4);
  for (std::int32_t v : items) append_le32(out, &v);
  return out;
}

void write_npy_item_buffer(const std::string& path, int height, int width,
                           const std::vector<std::int32_t>& items) {
  const std::string out = encode_npy_item_buffer(height, width, items);
  write_file_atomic(path, out.data(), out.size());
}

ItemBufferFile read_npy_item_buffer(const std::string& path) {
  const std::string data = read_whole_file(path);
  if (data.size() < 10 || data.compare(0, 6, "\x93NUMPY", 6) != 0)
    throw InputError(path + ": not a .npy file");
  if (data[6] != 1) throw InputError(path + ": unsupported .npy version");
  const std::size_t header_len = static_cast<unsigned char>(data[8]) |
                                 (static_cast<std::size_t>(static_cast<unsigned char>(data[9])) << 8);
  if (data.size() < 10 + header_len) throw InputError(path + ": truncated .npy header");
  const std::string header = data.substr(10, header_len);
  auto fail = [&](const std::string& what) -> void { throw InputError(path + ": " + what); };
  if (header.find("'descr': '<i4'") == std::string::npos) fail("dtype is not '<i4'");
  if (header.find("'fortran_order': False") == std::string::npos) fail("not C order");
  const std::size_t shape_at = header.find("'shape': (");
  if (shape_at == std::string::npos) fail("no shape");
  long h = 0, w = 0, c = 0;
  if (std::sscanf(header.c_str() + shape_at, "'shape': (%ld, %ld, %ld)", &h, &w, &c) != 3 || c != 2 ||
      h <= 0 || w <= 0 || h > std::numeric_limits<int>::max() || w > std::numeric_limits<int>::max())
    fail("shape is not (H, W, 2)");
  ItemBufferFile file;
  file.height = static_cast<int>(h);
  file.width = static_cast<int>(w);
  const std::size_t count = static_cast<std::size_t>(h) * w * 2;
  if (data.size() - 10 - header_len != count * 4) fail("data size does not match the shape");
  file.items.resize(count);
  const char* raster = data.data() + 10 + header_len;
  for (std::size_t i = 0; i < count; ++i) file.items[i] = read_4<std::int32_t>(raster + 4 * i, true);
  return file;
}

// ------------------------------------------------------------------ PSNR

double psnr(const std::vector<float>& a, const std::vector<float>& b, double peak) {
  if (a.size() != b.size()) throw std::invalid_argument("psnr: buffers differ in size");
  if (a.empty()) return std::numeric_limits<double>::infinity();
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = static_cast<double>(a[i]) - static_cast<double>(b[i]);
    sum += d * d;
  }
  const double mse = sum / static_cast<double>(a.size());
  if (mse == 0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(peak * peak / mse);
}

}  // namespace opsila
