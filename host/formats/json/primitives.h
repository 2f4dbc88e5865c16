// Tessellation of the scene format's built-in shapes, plus the portable
// random numbers and noise its generators use. Every function appends
// triangles with CCW outward winding (CONTRACT's Ng points out of solids, up for
// planes) and returns the next free facet id.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "scene/scene.h"

namespace opsila {

// Who the appended triangles belong to.
struct FacetTag {
  int object_id = 0;
  int material = 0;
};

// Scale, then rotate about x, then y, then z (degrees, right-handed), then
// translate: p' = T * Rz * Ry * Rx * S * p.
struct Transform {
  Vec3 translate{0, 0, 0};
  Vec3 rotate_deg{0, 0, 0};
  Vec3 scale{1, 1, 1};
  bool is_identity() const;
  Vec3 apply(const Vec3& p) const;
  // A normal under the same transform: rotated, scaled by 1 / scale (the
  // inverse transpose), not normalised (shading normalises).
  Vec3 apply_normal(const Vec3& n) const;
  // The same in double, row-major 3 x 4 (row i: A[i][0..2], b[i]; x' = A x + b).
  std::array<double, 12> matrix() const;
};

// The matrix of T · Rz · Ry · Rx · S from values in double.
std::array<double, 12> transform_matrix(const double translate[3], const double rotate_deg[3], const double scale[3]);

// Applies `t` to the vertices of triangles [first, end).
void transform_triangles(std::vector<Triangle>& tris, std::size_t first, const Transform& t);

// Applies `t` to the vertex normals of attributes [first, end).
void transform_normals(std::vector<VertexAttributes>& attributes, std::size_t first, const Transform& t);

// Makes room for `more` triangles, growing geometrically: many small shapes
// appended one by one must not reallocate (and copy) every time.
void reserve_more(std::vector<Triangle>& tris, std::size_t more);

// Triangles an icosphere with `subdivisions` levels has: 20 * 4^subdivisions.
std::size_t icosphere_triangles(int subdivisions);

// A convex or star-shaped planar polygon (>= 3 vertices, in CCW order seen
// from the side its normal points to), fan-triangulated from vertex 0: one
// facet. Zero-area fan triangles are left out.
int add_polygon(std::vector<Triangle>& out, const std::vector<Vec3>& vertices, FacetTag tag,
                int facet);

// Icosahedron subdivided `subdivisions` times and pushed onto the sphere;
// every triangle is a facet.
int add_icosphere(std::vector<Triangle>& out, const Vec3& center, float radius,
                  int subdivisions, FacetTag tag, int facet);

// Axis-aligned box [lo, hi]: six quad facets (-x, +x, -y, +y, -z, +z).
int add_box(std::vector<Triangle>& out, const Vec3& lo, const Vec3& hi, FacetTag tag,
            int facet);

// Rectangle in the plane y = center[1] facing +y, size_x by size_z: one facet.
int add_plane(std::vector<Triangle>& out, const Vec3& center, float size_x, float size_z,
              FacetTag tag, int facet);

// The same rectangle cut into nx by nz square facets; square (i, j) (i along
// x, j along z, from the -x/-z corner) gets material_a when i + j is even.
int add_checkerboard(std::vector<Triangle>& out, const Vec3& center, float size_x,
                     float size_z, int nx, int nz, int object_id, int material_a,
                     int material_b, int facet);

struct TerrainDesc {
  Vec3 center{0, 0, 0};  // middle of the base rectangle
  float size_x = 10, size_z = 10;
  int quads_x = 64, quads_z = 64;
  float height = 1;      // the noise (in [0, 1]) is scaled by this
  float features = 4;    // noise cells across the terrain (lowest octave)
  int octaves = 4;       // each halves amplitude and doubles frequency
  std::uint64_t seed = 1;
};

// Heightfield of quads_x * quads_z quads, two triangle facets each (quad
// (i, j) gives facets 2k and 2k+1 with k = j * quads_x + i). With two
// materials the quads alternate like a checkerboard.
int add_terrain(std::vector<Triangle>& out, const TerrainDesc& desc, int object_id,
                int material_a, int material_b, int facet);

// The terrain's triangle count, 2 * quads_x * quads_z.
std::size_t terrain_triangles(const TerrainDesc& desc);

// Only the terrain's triangles [begin, end) in add_terrain's order (quad by
// quad, row by row), computing only the lattice rows they touch: a rank of
// a scene read in shares makes only its window. Facet ids are
// `facet` + the triangle's index, as in the whole terrain.
void add_terrain_window(std::vector<Triangle>& out, const TerrainDesc& desc, int object_id, int material_a,
                        int material_b, int facet, std::size_t begin, std::size_t end);

// Terrain height at lattice point (i, j) in [0, 1]: fractal value noise from
// integer hashing only, so every platform gets the same numbers.
double terrain_noise(const TerrainDesc& desc, int i, int j);

// terrain_noise at every point (0..quads_x, j) of row j, into out: the same
// numbers, each lattice value hashed once per cell the row crosses.
void terrain_noise_row(const TerrainDesc& desc, int j, std::vector<double>& out);

// PCG32 (O'Neill): the same sequence on every compiler and library, unlike
// the std:: distributions.
class Pcg32 {
 public:
  explicit Pcg32(std::uint64_t seed, std::uint64_t stream = 54u);
  std::uint32_t next();
  double uniform();                          // [0, 1), 32 random bits
  double uniform(double lo, double hi);      // [lo, hi)
  int below(int n);                          // [0, n), n > 0
 private:
  std::uint64_t state_ = 0, inc_ = 0;
};

}  // namespace opsila
