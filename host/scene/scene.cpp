// The scene model: CONTRACT material rules, bounds, epsilon, auto-framing.
#include "scene/scene.h"

#include "scene/instances.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.h"
#include "core/parallel.h"
#include "opsila_shared.h"

namespace opsila {

bool illum_reflects(int illum) { return illum >= 3 && illum <= 7; }
bool illum_transmits(int illum) { return illum == 4 || illum == 6 || illum == 7; }

namespace {

std::string short_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}
}  // namespace

std::string spp_problem(long long n) {
  const std::string squares = "1, 4, 9, 16, ..., " + std::to_string(kMaxSpp);
  if (n < 1 || n > kMaxSpp) return "samples per pixel must be a square in " + squares;
  const long long k = std::llround(std::sqrt(double(n)));
  if (k * k != n) return "samples per pixel must be a square (k x k grid): " + squares;
  return "";
}

int spp_side(int n) { return static_cast<int>(std::llround(std::sqrt(double(n)))); }

std::string material_value_problem(const std::string& key, float value) {
  (void)key;  // the same rule for every key today; named for the callers' messages
  if (!std::isfinite(value)) return "must be a finite number";
  if (value < 0) return "must not be negative (" + short_number(value) + ")";
  return "";
}

Vec3 MaterialDesc::kr() const { return illum_reflects(illum) ? ks : Vec3{0, 0, 0}; }

Vec3 MaterialDesc::kt() const { return illum_transmits(illum) ? tf : Vec3{0, 0, 0}; }

Vec3 left_out_colour(bool has_map) { return has_map ? Vec3{1, 1, 1} : Vec3{0, 0, 0}; }

MaterialDesc MaterialDesc::default_material() {
  MaterialDesc m;
  m.name = "default";
  m.ka = {0.8f, 0.8f, 0.8f};
  m.kd = {0.8f, 0.8f, 0.8f};
  m.ks = {0, 0, 0};
  m.tf = {0, 0, 0};
  m.ns = 1.0f;
  m.ni = 1.0f;
  m.illum = 2;
  return m;
}

void append_warnings(Scene& into, Scene& from) {
  for (MapRequest& r : from.map_requests) {
    r.warning += into.warnings.size();
    into.map_requests.push_back(std::move(r));
  }
  for (std::string& w : from.warnings) into.warnings.push_back(std::move(w));
  from.map_requests.clear();
  from.warnings.clear();
}

void put_warnings_first(Scene& scene, std::vector<std::string> first) {
  for (MapRequest& r : scene.map_requests) r.warning += first.size();
  for (std::string& w : scene.warnings) first.push_back(std::move(w));
  scene.warnings = std::move(first);
}

void Scene::keep_figures() {
  if (by_figures()) return;
  bounds(share.lo, share.hi);
  share.total_triangles = triangles.size();
  share.banked = true;
}

void Scene::release_triangles() {
  keep_figures();
  std::vector<Triangle>().swap(triangles);
}

void Scene::bounds(Vec3& lo, Vec3& hi) const {
  if (by_figures()) {
    lo = share.lo, hi = share.hi;
    return;
  }
  if (triangles.empty() && instances.empty()) {
    lo = hi = Vec3{0, 0, 0};
    return;
  }
  own_bounds(lo, hi);
  // Instances: their world boxes (scene/instances.h), which hold them.
  for (const InstanceDesc& in : instances) {
    Vec3 l, h;
    instance_box(*this, in, l, h);
    lo = min(lo, l);
    hi = max(hi, h);
  }
}

void Scene::own_bounds(Vec3& lo, Vec3& hi) const {
  // Called by the loader, the partition and the frame constants: on 8 M
  // facets a loop over the vertices by pointer cost 0.2 s a call, this one,
  // with one running bound per axis in registers, some 20 ms; large scenes
  // are scanned in chunks on the host threads, joined in order (a tie
  // between -0 and +0 keeps the first met, as one scan does).
  const float inf = std::numeric_limits<float>::infinity();
  constexpr std::size_t kChunkFacets = std::size_t(1) << 18;
  const std::size_t n = triangles.size();
  const std::size_t chunks = n < 2 * kChunkFacets ? 1 : std::size_t(host_threads());
  std::vector<std::array<float, 6>> part(chunks);
  parallel_for(chunks, [&](std::size_t k) {
    float lx = inf, ly = inf, lz = inf, hx = -inf, hy = -inf, hz = -inf;
    for (std::size_t i = n * k / chunks, e = n * (k + 1) / chunks; i < e; ++i) {
      const Triangle& t = triangles[i];
      lx = std::min({lx, t.v0[0], t.v1[0], t.v2[0]});
      ly = std::min({ly, t.v0[1], t.v1[1], t.v2[1]});
      lz = std::min({lz, t.v0[2], t.v1[2], t.v2[2]});
      hx = std::max({hx, t.v0[0], t.v1[0], t.v2[0]});
      hy = std::max({hy, t.v0[1], t.v1[1], t.v2[1]});
      hz = std::max({hz, t.v0[2], t.v1[2], t.v2[2]});
    }
    part[k] = {lx, ly, lz, hx, hy, hz};
  });
  lo = {inf, inf, inf};
  hi = {-inf, -inf, -inf};
  for (const std::array<float, 6>& p : part)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[3 + a]);
}

double Scene::diagonal() const {
  Vec3 lo, hi;
  bounds(lo, hi);
  return box_diagonal(lo, hi);
}

double box_diagonal(const Vec3& lo, const Vec3& hi) {
  double sum = 0;
  for (int a = 0; a < 3; ++a) {
    const double d = double(hi[a]) - double(lo[a]);
    sum += d * d;
  }
  return std::sqrt(sum);
}

float Scene::epsilon() const { return epsilon_for(diagonal()); }

CameraDesc frame_bounds(const Vec3& lo, const Vec3& hi, float fov_deg, float aspect) {
  CameraDesc cam;
  double centre[3], r2 = 0;
  for (int a = 0; a < 3; ++a) {
    centre[a] = 0.5 * (double(lo[a]) + double(hi[a]));
    const double half = 0.5 * (double(hi[a]) - double(lo[a]));
    r2 += half * half;
  }
  double r = std::sqrt(r2);
  // A point-sized (or broken) box still gets a usable camera.
  if (!(r > 0) || !std::isfinite(r)) r = 1.0;
  const double pi = 3.14159265358979323846;
  const double fov_v = double(fov_deg) * pi / 180.0;
  const double fov_h = 2.0 * std::atan(std::tan(fov_v / 2.0) * double(aspect));
  const double d = r / std::sin(std::min(fov_v, fov_h) / 2.0);
  cam.look_at = {float(centre[0]), float(centre[1]), float(centre[2])};
  // Seen from the front, right and above: no axis-aligned plane (a flat
  // model, a floor, a wall) is ever seen edge-on.
  const double k = d / std::sqrt(6.0);  // d * normalize(1, 1, 2)
  cam.eye = {float(centre[0] + k), float(centre[1] + k), float(centre[2] + 2.0 * k)};
  cam.up = {0, 1, 0};
  cam.fov_deg = fov_deg;
  return cam;
}

void check_scene_extent(const Scene& scene, const std::string& where) {
  Vec3 lo, hi;
  scene.bounds(lo, hi);
  check_scene_extent(scene.total_triangles() + scene.instances.size(), lo, hi, where);  // an instance has facets
}

void check_scene_extent(std::size_t triangles, const Vec3& lo, const Vec3& hi, const std::string& where) {
  if (triangles == 0) throw InputError(where + ": no facets");
  if (const std::string beyond = scene_extent_beyond(lo, hi); !beyond.empty()) throw InputError(where + ": " + beyond);
  const double diag = box_diagonal(lo, hi);
  const float diag_f = static_cast<float>(diag);
  const float eps = epsilon_for(diag);
  if (!(diag_f > 0) || !(eps > 0) || !std::isfinite(eps))
    throw InputError(where + ": scene has no extent (bounding-box diagonal " +
                     short_number(diag) + ", so epsilon is not positive)");
}

std::string scene_extent_beyond(const Vec3& lo, const Vec3& hi) {
  const double diag = box_diagonal(lo, hi);
  if (!std::isfinite(static_cast<float>(diag)))
    return "scene extent overflows float (bounding-box diagonal " + short_number(diag) + ")";
  if (diag > kMaxSceneExtent)
    return "scene extent too large (bounding-box diagonal " + short_number(diag) + ", the limit is " +
           short_number(kMaxSceneExtent) + ")";
  return "";
}

void check_material_count(std::size_t materials, const std::string& where) {
  if (materials > std::size_t(OPSILA_MAX_MATERIALS))
    throw InputError(where + "more than " + std::to_string(OPSILA_MAX_MATERIALS) +
                     " materials, the most opsila renders (docs/CONTRACT.md, Limits)");
}

void check_fan_triangles(long long triangles, const std::string& where) {
  if (triangles > OPSILA_MAX_FAN)
    throw InputError(where + "the facet fans into " + std::to_string(triangles) + " triangles, more than " +
                     std::to_string(OPSILA_MAX_FAN) + ", the most one facet may have (docs/CONTRACT.md, Limits)");
}

// What the hit order (kernels/hit_order.h) needs of the ids: a material
// index and a fan index that fit their halves of BankTriangle::material_fan
// (user limits: one line), and facet ids that never decrease as object ids
// increase, so that comparing facet ids orders by object first (every
// reader numbers them so: a failure here is a reader's fault).
void check_hit_order_ids(const Scene& scene) {
  std::vector<std::pair<int, int>> facets;  // per object id: least and greatest facet id
  for (const Triangle& t : scene.triangles) {
    if (t.material >= OPSILA_MAX_MATERIALS)
      throw InputError("the scene has more than " + std::to_string(OPSILA_MAX_MATERIALS) +
                       " materials, the most opsila renders (docs/CONTRACT.md, Limits)");
    if (t.fan >= OPSILA_MAX_FAN)
      throw InputError("facet " + std::to_string(t.facet_id) + " (object " + std::to_string(t.object_id) +
                       ") has more than " + std::to_string(OPSILA_MAX_FAN) +
                       " triangles (its polygon's fan, times its mesh's placements), the most opsila "
                       "renders (docs/CONTRACT.md, Limits)");
    if (std::size_t(t.object_id) >= facets.size()) facets.resize(std::size_t(t.object_id) + 1, {INT_MAX, -1});
    auto& f = facets[std::size_t(t.object_id)];
    f = {std::min(f.first, t.facet_id), std::max(f.second, t.facet_id)};
  }
  int below = -1;  // the greatest facet id of the objects before
  for (std::size_t o = 0; o < facets.size(); ++o) {
    if (facets[o].second < 0) continue;
    if (facets[o].first <= below)
      throw std::logic_error("facet ids do not increase with object ids (object " + std::to_string(o) +
                             "): the hit order would not be the contract's");
    below = facets[o].second;
  }
}

}  // namespace opsila
