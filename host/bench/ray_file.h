// The traversal alone's workload as one file (`opsila bench --rays-out
// FILE.rays`): the scene's triangles, the rays the megakernel traced and
// opsila's answer for each, so that another traversal kernel can be timed
// on the same rays and checked against the same answers
// (docs/BENCHMARKS.md, "The rays file"). Little-endian, 4-byte fields:
//   header   char magic[8] "OPSILARY", u32 version (1), u32 triangles T,
//            u32 nearest-hit rays N, u32 any-hit rays A           (24 bytes)
//   T x 9 f32  v0, v1, v2 of each triangle (world space)
//   N x 8 f32  origin xyz, tmin, direction xyz, tmax (+inf)
//   A x 8 f32  origin xyz, tmin, direction xyz, tmax (the segment's end)
//   N x i32    the triangle hit first (its index above), -1 for none
//   A x i32    1 when a triangle blocks the segment (tmin, tmax), else 0
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace opsila {

struct RayFile {
  std::vector<float> triangles;           // 9 per triangle
  std::vector<float> nearest, any;        // 8 per ray
  std::vector<std::int32_t> nearest_hit;  // one per nearest-hit ray
  std::vector<std::int32_t> any_blocked;  // one per any-hit ray
};

constexpr char kRayFileMagic[8] = {'O', 'P', 'S', 'I', 'L', 'A', 'R', 'Y'};
constexpr std::uint32_t kRayFileVersion = 1;

// The file's bytes. The counts must agree (9 floats a triangle, 8 a ray,
// one answer a ray).
std::string ray_file_bytes(const RayFile& f);
// Parses bytes written by ray_file_bytes; throws InputError naming `what`
// and the field for a wrong magic, version or size.
RayFile parse_ray_file(const std::string& bytes, const std::string& what);

}  // namespace opsila
