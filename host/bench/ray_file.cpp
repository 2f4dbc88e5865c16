#include "bench/ray_file.h"

#include <cstring>

#include "core/errors.h"

namespace opsila {

namespace {

constexpr std::size_t kHeaderBytes = 24;

template <typename T>
void put(std::string& out, const std::vector<T>& v) {
  if (!v.empty()) out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

void put_u32(std::string& out, std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); }

std::uint32_t get_u32(const std::string& bytes, std::size_t at) {
  std::uint32_t v;
  std::memcpy(&v, bytes.data() + at, 4);
  return v;
}

// n elements from `at` on, `at` moved past them.
template <typename T>
std::vector<T> take(const std::string& bytes, std::size_t& at, std::uint64_t n) {
  std::vector<T> v(n);
  if (n > 0) std::memcpy(v.data(), bytes.data() + at, n * sizeof(T));  // an empty vector's data() may be null
  at += n * sizeof(T);
  return v;
}

}  // namespace

std::string ray_file_bytes(const RayFile& f) {
  std::string out(kRayFileMagic, sizeof kRayFileMagic);
  put_u32(out, kRayFileVersion);
  put_u32(out, static_cast<std::uint32_t>(f.triangles.size() / 9));
  put_u32(out, static_cast<std::uint32_t>(f.nearest.size() / 8));
  put_u32(out, static_cast<std::uint32_t>(f.any.size() / 8));
  put(out, f.triangles);
  put(out, f.nearest);
  put(out, f.any);
  put(out, f.nearest_hit);
  put(out, f.any_blocked);
  return out;
}

RayFile parse_ray_file(const std::string& bytes, const std::string& what) {
  if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kRayFileMagic, sizeof kRayFileMagic) != 0)
    throw InputError(what + ": not a rays file (magic OPSILARY expected)");
  if (get_u32(bytes, 8) != kRayFileVersion)
    throw InputError(what + ": version " + std::to_string(get_u32(bytes, 8)) + ", expected " +
                     std::to_string(kRayFileVersion));
  const std::uint64_t t = get_u32(bytes, 12), n = get_u32(bytes, 16), a = get_u32(bytes, 20);
  const std::uint64_t want = kHeaderBytes + 4 * (9 * t + 8 * (n + a) + n + a);
  if (bytes.size() != want)
    throw InputError(what + ": " + std::to_string(bytes.size()) + " bytes, the header's counts need " +
                     std::to_string(want));
  RayFile f;
  std::size_t at = kHeaderBytes;
  f.triangles = take<float>(bytes, at, 9 * t);
  f.nearest = take<float>(bytes, at, 8 * n);
  f.any = take<float>(bytes, at, 8 * a);
  f.nearest_hit = take<std::int32_t>(bytes, at, n);
  f.any_blocked = take<std::int32_t>(bytes, at, a);
  return f;
}

}  // namespace opsila
