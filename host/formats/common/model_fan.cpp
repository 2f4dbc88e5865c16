#include "formats/common/model_fan.h"

#include <algorithm>
#include <climits>

#ifdef OPSILA_HAVE_ASSIMP
#include <algorithm>
#include <cmath>

#include "core/errors.h"
#include "opsila_shared.h"

namespace opsila {

namespace {

bool finite3(const Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

}  // namespace

MeshFan::MeshFan(const std::string& name, const aiMesh& mesh, const aiMatrix4x4& place, std::size_t max_triangles,
                 FanTally& tally)
    : name_(name), mesh_(mesh), place_(place), normal_matrix_(place), max_triangles_(max_triangles), tally_(tally) {
  normal_matrix_.Inverse().Transpose();
  const double a = place.a1, b = place.a2, c = place.a3, d = place.b1, e = place.b2, f = place.b3, g = place.c1,
               h = place.c2, i = place.c3;
  mirrored_ = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g) < 0;
}

bool MeshFan::face(const unsigned* corners, unsigned n, unsigned f, int object, int facet, int material, Scene* out) {
  if (tally_.triangles + n > max_triangles_)
    throw TooManyTriangles(name_ + ": too many triangles (more than " + std::to_string(max_triangles_) + ")");
  const auto position = [&](unsigned i) {
    const aiVector3D p = place_ * mesh_.mVertices[i];
    return Vec3{p.x, p.y, p.z};
  };
  const auto where = [&] { return name_ + ": mesh " + std::to_string(object) + " face " + std::to_string(f); };
  // Its placements before this one share its facet ids: their fans count.
  const long long fan = (long long)(placement + 1) * ((long long)n - 2);
  if (fan > OPSILA_MAX_FAN)
    check_fan_triangles(fan, where() + (placement > 0 ? " (placement " + std::to_string(placement + 1) + ")" : "") + ": ");
  const Vec3 p0 = position(corners[0]);
  bool any = false;
  for (unsigned k = 1; k + 1 < n; ++k) {
    // A mirroring placement turns the winding: its fan triangles are taken
    // the other way round, so that Ng points out of the solid as it did in
    // the mesh's own frame (glTF 2.0, "Transformations").
    const unsigned corner[3] = {corners[0], corners[mirrored_ ? k + 1 : k], corners[mirrored_ ? k : k + 1]};
    Triangle t;
    t.v0 = p0;
    t.v1 = position(corner[1]);
    t.v2 = position(corner[2]);
    if (!finite3(t.v0) || !finite3(t.v1) || !finite3(t.v2))
      throw InputError(where() + ": a vertex is not a finite number");
    const double e1[3] = {double(t.v1[0]) - t.v0[0], double(t.v1[1]) - t.v0[1], double(t.v1[2]) - t.v0[2]};
    const double e2[3] = {double(t.v2[0]) - t.v0[0], double(t.v2[1]) - t.v0[1], double(t.v2[2]) - t.v0[2]};
    const float c[3] = {float(e1[1] * e2[2] - e1[2] * e2[1]), float(e1[2] * e2[0] - e1[0] * e2[2]),
                        float(e1[0] * e2[1] - e1[1] * e2[0])};
    if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2]))
      throw InputError(where() + ": facet too large: its edge vectors overflow float");
    if (c[0] == 0 && c[1] == 0 && c[2] == 0) {
      ++tally_.degenerate;
      continue;
    }
    ++tally_.triangles;
    for (int a = 0; a < 3; ++a) {
      tally_.lo[a] = std::min({tally_.lo[a], t.v0[a], t.v1[a], t.v2[a]});
      tally_.hi[a] = std::max({tally_.hi[a], t.v0[a], t.v1[a], t.v2[a]});
    }
    any = true;
    if (!out) continue;
    t.facet_id = facet;
    t.fan = static_cast<int>(std::min<long long>(INT_MAX, (long long)placement * (n - 2) + (k - 1)));
    t.object_id = object;
    t.material = material;
    if (mesh_.HasNormals() || mesh_.HasTextureCoords(0)) t.attributes = attributes(corner, *out);
    out->triangles.push_back(t);
  }
  return any;
}

int MeshFan::attributes(const unsigned* corner, Scene& out) const {
  const bool normals = mesh_.HasNormals(), uvs = mesh_.HasTextureCoords(0);
  VertexAttributes a;
  a.has_normals = normals;
  a.has_uv = uvs;
  for (int c = 0; c < 3; ++c) {
    if (normals) {
      const aiVector3D n = normal_matrix_ * mesh_.mNormals[corner[c]];
      a.normal[c] = Vec3{n.x, n.y, n.z};
      a.has_normals = a.has_normals && finite3(a.normal[c]);
    }
    if (uvs) {
      const aiVector3D& t = mesh_.mTextureCoords[0][corner[c]];
      a.uv[c] = {t.x, t.y};
      a.has_uv = a.has_uv && std::isfinite(t.x) && std::isfinite(t.y);
    }
  }
  if (!a.has_normals && !a.has_uv) return -1;
  out.attributes.push_back(a);
  return static_cast<int>(out.attributes.size()) - 1;
}

WindowFan::WindowFan(const std::string& path, const aiMesh& mesh, std::size_t max_triangles, const ModelWindow& window,
                     Scene& scene)
    : path_(path), window_(window), scene_(scene), fan_(path, mesh, aiMatrix4x4(), max_triangles, tally_) {
  scene_.has_camera = false;
  scene_.has_lights = false;
  scene_.materials.push_back(MaterialDesc::default_material());
}

void WindowFan::face(const unsigned* corner, unsigned n, unsigned f) {
  if (facets_ == INT_MAX) throw InputError(path_ + ": too many facets for 32-bit ids");
  const int owner = window_.fans > 0 ? window_owner(window_, fans_) : -1;
  fans_ += n - 2;
  const bool mine = owner >= 0 && owner == window_.rank;
  if (fan_.face(corner, n, f, 0, facets_, 0, mine ? &scene_ : nullptr) && owner >= 0)
    lowest_ = std::min(lowest_, owner), highest_ = std::max(highest_, owner);
  ++facets_;
}

void WindowFan::finish(std::uint64_t& fans) {
  scene_.num_objects = 1;
  scene_.num_facets = facets_;
  scene_.warnings = fan_warnings(path_, skipped_, 0, tally_.degenerate);
  if (tally_.triangles == 0) throw InputError(path_ + ": no facets (the model has no drawable polygons)");
  check_scene_extent(tally_.triangles, tally_.lo, tally_.hi, path_);
  scene_.camera = frame_bounds(tally_.lo, tally_.hi, 45.0f, float(scene_.width) / float(scene_.height));
  scene_.share.rank = window_.rank;
  scene_.share.ranks = window_.ranks;
  scene_.share.total_triangles = tally_.triangles;
  scene_.share.lo = tally_.lo;
  scene_.share.hi = tally_.hi;
  if (lowest_ < highest_) scene_.share.spread.push_back(0);
  scene_.input_files.push_back(path_);
  fans = fans_;
}

std::vector<std::string> fan_warnings(const std::string& name, long long skipped, int unplaced,
                                      long long degenerate) {
  std::vector<std::string> out;
  if (skipped > 0)
    out.push_back(name + ": " + std::to_string(skipped) +
                  " point or line primitive(s) skipped; they are not facets and get no id");
  if (unplaced > 0)
    out.push_back(name + ": " + std::to_string(unplaced) +
                  " mesh(es) not placed by any node of the scene are not drawn (their ids are kept)");
  if (degenerate > 0)
    out.push_back(name + ": " + std::to_string(degenerate) +
                  " degenerate (zero-area) triangle(s) not rendered; facet ids are kept");
  return out;
}

}  // namespace opsila
#endif
