// Built-in shapes of the scene format. Vertices shared by neighbouring
// facets are computed by the same expression from the same inputs, so they
// are bit-identical and the surfaces are watertight.
#include "formats/json/primitives.h"

#include <algorithm>
#include <cmath>

#include "core/page_ledger.h"
#include "core/parallel.h"

namespace opsila {

namespace {

constexpr double kPi = 3.14159265358979323846;

// cos/sin of an angle in degrees, exact at multiples of 90 so that
// "rotate 90" gives clean axis-aligned results.
void cos_sin_deg(double deg, double& c, double& s) {
  const double q = deg / 90.0;
  if (std::nearbyint(q) == q && std::fabs(q) < 1e9) {
    const long long k = ((static_cast<long long>(q) % 4) + 4) % 4;
    static const double cs[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    c = cs[k][0];
    s = cs[k][1];
    return;
  }
  const double r = deg * kPi / 180.0;
  c = std::cos(r);
  s = std::sin(r);
}

// fan: the triangle's index in its facet's fan (a facet of one triangle: 0).
void push(std::vector<Triangle>& out, const Vec3& a, const Vec3& b, const Vec3& c,
          FacetTag tag, int facet, int fan = 0) {
  Triangle t;
  t.fan = fan;
  t.v0 = a;
  t.v1 = b;
  t.v2 = c;
  t.facet_id = facet;
  t.object_id = tag.object_id;
  t.material = tag.material;
  out.push_back(t);
}

bool zero_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  const float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const float x = e1[1] * e2[2] - e1[2] * e2[1];
  const float y = e1[2] * e2[0] - e1[0] * e2[2];
  const float z = e1[0] * e2[1] - e1[1] * e2[0];
  return x == 0 && y == 0 && z == 0;
}

struct D3 {
  double x, y, z;
};

D3 unit(const D3& v) {
  const double n = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
  return {v.x / n, v.y / n, v.z / n};
}

// Midpoint on the sphere; symmetric in (a, b), so both facets sharing an edge
// get the same vertex.
D3 mid(const D3& a, const D3& b) { return unit({a.x + b.x, a.y + b.y, a.z + b.z}); }

// The unit sphere's triangles, three corners each, in facet order.
void unit_sphere(const D3& a, const D3& b, const D3& c, int level, std::vector<D3>& out) {
  if (level == 0) {
    out.insert(out.end(), {a, b, c});
    return;
  }
  const D3 ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
  unit_sphere(a, ab, ca, level - 1, out);
  unit_sphere(b, bc, ab, level - 1, out);
  unit_sphere(c, ca, bc, level - 1, out);
  unit_sphere(ab, bc, ca, level - 1, out);
}

std::vector<D3> unit_icosphere(int subdivisions) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  const D3 v[12] = {unit({-1, t, 0}), unit({1, t, 0}),   unit({-1, -t, 0}), unit({1, -t, 0}),
                    unit({0, -1, t}), unit({0, 1, t}),   unit({0, -1, -t}), unit({0, 1, -t}),
                    unit({t, 0, -1}), unit({t, 0, 1}),   unit({-t, 0, -1}), unit({-t, 0, 1})};
  static const int faces[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                   {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                   {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                   {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  std::vector<D3> out;
  out.reserve(3 * icosphere_triangles(subdivisions));
  for (const auto& f : faces) unit_sphere(v[f[0]], v[f[1]], v[f[2]], subdivisions, out);
  return out;
}

// Scenes of many spheres of a few sizes of mesh: each mesh is made once per
// thread and placed for every sphere (the midpoints' roots and divisions
// were most of a generated crowd's parse). Small meshes only (5 levels:
// 1.5 MB), so that the copies kept stay small.
constexpr int kKeptSubdivisions = 5;

const std::vector<D3>& kept_unit_icosphere(int subdivisions) {
  thread_local std::vector<D3> kept[kKeptSubdivisions + 1];
  std::vector<D3>& mesh = kept[subdivisions];
  if (mesh.empty()) mesh = unit_icosphere(subdivisions);
  return mesh;
}

// The rotation's cosines and sines, taken once for a run of points.
struct Turn {
  double c[3], s[3];
  explicit Turn(const Vec3& deg) {
    for (int a = 0; a < 3; ++a) cos_sin_deg(deg[a], c[a], s[a]);
  }
  explicit Turn(const double deg[3]) {
    for (int a = 0; a < 3; ++a) cos_sin_deg(deg[a], c[a], s[a]);
  }
};

// (x, y, z) rotated about x, then y, then z.
void turn_point(const Turn& turn, double& x, double& y, double& z) {
  double c = turn.c[0], s = turn.s[0];  // about x
  double y2 = c * y - s * z, z2 = s * y + c * z;
  y = y2;
  z = z2;
  c = turn.c[1], s = turn.s[1];  // about y
  double x2 = c * x + s * z;
  z2 = -s * x + c * z;
  x = x2;
  z = z2;
  c = turn.c[2], s = turn.s[2];  // about z
  x2 = c * x - s * y;
  y2 = s * x + c * y;
  x = x2;
  y = y2;
}

Vec3 apply_turned(const Transform& t, const Turn& turn, const Vec3& p) {
  double x = double(p[0]) * t.scale[0], y = double(p[1]) * t.scale[1], z = double(p[2]) * t.scale[2];
  turn_point(turn, x, y, z);
  return {static_cast<float>(x + t.translate[0]), static_cast<float>(y + t.translate[1]),
          static_cast<float>(z + t.translate[2])};
}

Transform normal_transform(const Transform& t) {
  Transform r;
  r.rotate_deg = t.rotate_deg;
  for (int a = 0; a < 3; ++a) r.scale[a] = static_cast<float>(1.0 / double(t.scale[a]));
  return r;
}

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Lattice value in [0, 1) for cell (x, z) of octave o.
double lattice(std::uint64_t seed, long long x, long long z, int o) {
  std::uint64_t h = splitmix64(seed);
  h = splitmix64(h ^ static_cast<std::uint64_t>(x));
  h = splitmix64(h ^ static_cast<std::uint64_t>(z));
  h = splitmix64(h ^ static_cast<std::uint64_t>(o));
  return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0);
}

double smooth(double t) { return t * t * (3.0 - 2.0 * t); }

}  // namespace

bool Transform::is_identity() const {
  return translate == Vec3{0, 0, 0} && rotate_deg == Vec3{0, 0, 0} && scale == Vec3{1, 1, 1};
}

Vec3 Transform::apply(const Vec3& p) const { return apply_turned(*this, Turn(rotate_deg), p); }

Vec3 Transform::apply_normal(const Vec3& n) const { return normal_transform(*this).apply(n); }

std::array<double, 12> Transform::matrix() const {
  const double t[3] = {translate[0], translate[1], translate[2]}, r[3] = {rotate_deg[0], rotate_deg[1], rotate_deg[2]},
               s[3] = {scale[0], scale[1], scale[2]};
  return transform_matrix(t, r, s);
}

std::array<double, 12> transform_matrix(const double translate[3], const double rotate_deg[3], const double scale[3]) {
  const Turn turn(rotate_deg);
  std::array<double, 12> m{};
  for (int j = 0; j < 3; ++j) {  // column j: the turned, scaled axis j
    double p[3] = {0, 0, 0};
    p[j] = scale[j];
    turn_point(turn, p[0], p[1], p[2]);
    for (int r = 0; r < 3; ++r) m[std::size_t(4 * r + j)] = p[r];
  }
  for (int r = 0; r < 3; ++r) m[std::size_t(4 * r + 3)] = translate[r];
  return m;
}

void transform_normals(std::vector<VertexAttributes>& attributes, std::size_t first, const Transform& t) {
  if (t.is_identity()) return;
  const Transform normal = normal_transform(t);
  const Turn turn(normal.rotate_deg);
  for (std::size_t i = first; i < attributes.size(); ++i)
    if (attributes[i].has_normals)
      for (Vec3& n : attributes[i].normal) n = apply_turned(normal, turn, n);
}

void transform_triangles(std::vector<Triangle>& tris, std::size_t first, const Transform& t) {
  if (t.is_identity()) return;
  const Turn turn(t.rotate_deg);
  for (std::size_t i = first; i < tris.size(); ++i) {
    tris[i].v0 = apply_turned(t, turn, tris[i].v0);
    tris[i].v1 = apply_turned(t, turn, tris[i].v1);
    tris[i].v2 = apply_turned(t, turn, tris[i].v2);
  }
}

void reserve_more(std::vector<Triangle>& tris, std::size_t more) {
  const std::size_t need = tris.size() + more;
  // A quarter more than the capacity, moved without two whole copies at
  // once: a rank's windowed terrain is most of its memory, and every entry
  // after it grows the same array.
  if (need > tris.capacity()) move_to_capacity(tris, std::max(need, tris.capacity() + tris.capacity() / 4));
}

std::size_t icosphere_triangles(int subdivisions) {
  return std::size_t(20) << (2 * subdivisions);
}

int add_polygon(std::vector<Triangle>& out, const std::vector<Vec3>& vertices, FacetTag tag,
                int facet) {
  for (std::size_t k = 1; k + 1 < vertices.size(); ++k) {
    if (zero_area(vertices[0], vertices[k], vertices[k + 1])) continue;
    push(out, vertices[0], vertices[k], vertices[k + 1], tag, facet, static_cast<int>(k - 1));
  }
  return facet + 1;
}

int add_icosphere(std::vector<Triangle>& out, const Vec3& center, float radius,
                  int subdivisions, FacetTag tag, int facet) {
  reserve_more(out, icosphere_triangles(subdivisions));
  std::vector<D3> made;
  const std::vector<D3>& mesh = subdivisions <= kKeptSubdivisions ? kept_unit_icosphere(subdivisions)
                                                                   : (made = unit_icosphere(subdivisions));
  const double cx = center[0], cy = center[1], cz = center[2], r = radius;
  const auto place = [&](const D3& u) {
    return Vec3{static_cast<float>(cx + r * u.x), static_cast<float>(cy + r * u.y), static_cast<float>(cz + r * u.z)};
  };
  for (std::size_t k = 0; k < mesh.size(); k += 3)
    push(out, place(mesh[k]), place(mesh[k + 1]), place(mesh[k + 2]), tag, facet++);
  return facet;
}

int add_box(std::vector<Triangle>& out, const Vec3& lo, const Vec3& hi, FacetTag tag,
            int facet) {
  const float x0 = lo[0], y0 = lo[1], z0 = lo[2], x1 = hi[0], y1 = hi[1], z1 = hi[2];
  const Vec3 quads[6][4] = {
      {{x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}},  // -x
      {{x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1}},  // +x
      {{x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}},  // -y
      {{x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1}, {x1, y1, z0}},  // +y
      {{x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, {x1, y0, z0}},  // -z
      {{x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}},  // +z
  };
  for (const auto& q : quads) {
    push(out, q[0], q[1], q[2], tag, facet, 0);
    push(out, q[0], q[2], q[3], tag, facet, 1);
    ++facet;
  }
  return facet;
}

int add_plane(std::vector<Triangle>& out, const Vec3& center, float size_x, float size_z,
              FacetTag tag, int facet) {
  return add_checkerboard(out, center, size_x, size_z, 1, 1, tag.object_id, tag.material,
                          tag.material, facet);
}

int add_checkerboard(std::vector<Triangle>& out, const Vec3& center, float size_x,
                     float size_z, int nx, int nz, int object_id, int material_a,
                     int material_b, int facet) {
  const double x0 = double(center[0]) - 0.5 * size_x, z0 = double(center[2]) - 0.5 * size_z;
  const float y = center[1];
  const auto gx = [&](int i) { return static_cast<float>(x0 + double(size_x) * i / nx); };
  const auto gz = [&](int j) { return static_cast<float>(z0 + double(size_z) * j / nz); };
  reserve_more(out, std::size_t(2) * nx * nz);
  for (int j = 0; j < nz; ++j) {
    for (int i = 0; i < nx; ++i) {
      const FacetTag tag{object_id, (i + j) % 2 == 0 ? material_a : material_b};
      // Corners in CCW order seen from +y: (x0,z0) (x0,z1) (x1,z1) (x1,z0).
      const Vec3 a{gx(i), y, gz(j)}, d{gx(i), y, gz(j + 1)}, c{gx(i + 1), y, gz(j + 1)},
          b{gx(i + 1), y, gz(j)};
      push(out, a, d, c, tag, facet, 0);
      push(out, a, c, b, tag, facet, 1);
      ++facet;
    }
  }
  return facet;
}

double terrain_noise(const TerrainDesc& desc, int i, int j) {
  double sum = 0, total = 0, amp = 1, freq = desc.features;
  for (int o = 0; o < desc.octaves; ++o) {
    const double u = freq * i / desc.quads_x, v = freq * j / desc.quads_z;
    const double fu = std::floor(u), fv = std::floor(v);
    const long long cu = static_cast<long long>(fu), cv = static_cast<long long>(fv);
    const double su = smooth(u - fu), sv = smooth(v - fv);
    const double h00 = lattice(desc.seed, cu, cv, o), h10 = lattice(desc.seed, cu + 1, cv, o);
    const double h01 = lattice(desc.seed, cu, cv + 1, o);
    const double h11 = lattice(desc.seed, cu + 1, cv + 1, o);
    const double top = h00 + (h10 - h00) * su, bottom = h01 + (h11 - h01) * su;
    sum += amp * (top + (bottom - top) * sv);
    total += amp;
    amp *= 0.5;
    freq *= 2.0;
  }
  return total > 0 ? sum / total : 0.0;
}

// The same sums as terrain_noise at every point of row j, octave by octave
// in the same order, so each height is bit for bit terrain_noise's. Along a
// row a cell's index never decreases, so each of its four lattice values is
// hashed once per cell met instead of once per point (a 708-quad row of the
// lowest octave, 4 cells: 8 hashes instead of 2,836).
void terrain_noise_row(const TerrainDesc& desc, int j, std::vector<double>& out) {
  const int n = desc.quads_x + 1;
  out.assign(std::size_t(n), 0.0);
  double total = 0, amp = 1, freq = desc.features;
  for (int o = 0; o < desc.octaves; ++o) {
    const double v = freq * j / desc.quads_z, fv = std::floor(v);
    const long long cv = static_cast<long long>(fv);
    const double sv = smooth(v - fv);
    long long cell = 0;
    double h00 = 0, h10 = 0, h01 = 0, h11 = 0;
    bool have = false;
    for (int i = 0; i < n; ++i) {
      const double u = freq * i / desc.quads_x, fu = std::floor(u);
      const long long cu = static_cast<long long>(fu);
      if (!have || cu != cell) {
        if (have && cu == cell + 1) {
          h00 = h10, h01 = h11;  // the next cell shares this one's right edge
        } else {
          h00 = lattice(desc.seed, cu, cv, o), h01 = lattice(desc.seed, cu, cv + 1, o);
        }
        h10 = lattice(desc.seed, cu + 1, cv, o), h11 = lattice(desc.seed, cu + 1, cv + 1, o);
        cell = cu, have = true;
      }
      const double su = smooth(u - fu);
      const double top = h00 + (h10 - h00) * su, bottom = h01 + (h11 - h01) * su;
      out[std::size_t(i)] += amp * (top + (bottom - top) * sv);
    }
    total += amp;
    amp *= 0.5;
    freq *= 2.0;
  }
  if (total > 0)
    for (double& h : out) h /= total;
}

int add_terrain(std::vector<Triangle>& out, const TerrainDesc& desc, int object_id,
                int material_a, int material_b, int facet) {
  const std::size_t all = terrain_triangles(desc);
  add_terrain_window(out, desc, object_id, material_a, material_b, facet, 0, all);
  return facet + static_cast<int>(all);
}

std::size_t terrain_triangles(const TerrainDesc& desc) { return std::size_t(2) * desc.quads_x * desc.quads_z; }

// Every lattice point the window needs is computed once, by the same
// expression whatever the window, so a window's triangles are bit for bit
// those of the whole terrain. The heights (the noise: most of the work) are
// computed first, rows side by side on the host threads; the triangles then
// follow in order.
void add_terrain_window(std::vector<Triangle>& out, const TerrainDesc& desc, int object_id, int material_a,
                        int material_b, int facet, std::size_t begin, std::size_t end) {
  const int nx = desc.quads_x, nz = desc.quads_z;
  end = std::min(end, terrain_triangles(desc));
  if (begin >= end) return;
  const double x0 = double(desc.center[0]) - 0.5 * desc.size_x;
  const double z0 = double(desc.center[2]) - 0.5 * desc.size_z;
  const std::size_t per_row = std::size_t(2) * nx, width = std::size_t(nx) + 1;
  const int j_first = static_cast<int>(begin / per_row), j_last = static_cast<int>((end - 1) / per_row);
  const std::size_t rows = std::size_t(j_last - j_first) + 2;  // j_first .. j_last + 1
  std::vector<float> height(rows * width);
  const std::size_t chunks = std::min<std::size_t>(rows, 8 * std::size_t(host_threads()));
  parallel_for(chunks, [&](std::size_t k) {
    std::vector<double> noise;
    for (std::size_t r = rows * k / chunks; r < rows * (k + 1) / chunks; ++r) {
      terrain_noise_row(desc, j_first + static_cast<int>(r), noise);
      for (int i = 0; i <= nx; ++i)
        height[r * width + std::size_t(i)] =
            static_cast<float>(desc.center[1] + desc.height * noise[std::size_t(i)]);
    }
  });
  const auto point = [&](int i, int j) {
    return Vec3{static_cast<float>(x0 + double(desc.size_x) * i / nx),
                height[std::size_t(j - j_first) * width + std::size_t(i)],
                static_cast<float>(z0 + double(desc.size_z) * j / nz)};
  };
  reserve_more(out, end - begin);
  for (int j = j_first; j <= j_last; ++j) {
    const std::size_t row_first = std::size_t(j) * per_row;
    const int i_first = j == j_first ? static_cast<int>((begin - row_first) / 2) : 0;
    const int i_end = j == j_last ? static_cast<int>((end - 1 - row_first) / 2) + 1 : nx;
    for (int i = i_first; i < i_end; ++i) {
      const FacetTag tag{object_id, (i + j) % 2 == 0 ? material_a : material_b};
      const Vec3 a = point(i, j), b = point(i + 1, j), c = point(i + 1, j + 1), d = point(i, j + 1);
      const std::size_t k = row_first + std::size_t(2) * i;  // the quad's first triangle
      if (k >= begin) push(out, a, d, c, tag, facet + static_cast<int>(k));
      if (k + 1 < end) push(out, a, c, b, tag, facet + static_cast<int>(k + 1));
    }
  }
}

Pcg32::Pcg32(std::uint64_t seed, std::uint64_t stream) : inc_((stream << 1u) | 1u) {
  next();
  state_ += seed;
  next();
}

std::uint32_t Pcg32::next() {
  const std::uint64_t old = state_;
  state_ = old * 6364136223846793005ull + inc_;
  const auto xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
  const auto rot = static_cast<std::uint32_t>(old >> 59u);
  return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
}

double Pcg32::uniform() { return next() * (1.0 / 4294967296.0); }

double Pcg32::uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

int Pcg32::below(int n) {
  const int k = static_cast<int>(uniform() * n);
  return k < n ? k : n - 1;
}

}  // namespace opsila
