// The scene sections of the JSON scene format (scenes/FORMAT.md): image,
// camera, lights, materials and transforms.
#include "formats/json/scene_sections.h"

#include <cmath>

#include "opsila_shared.h"
#include "formats/common/json_text.h"

namespace opsila {
namespace scene_json {

void SceneSections::image(const Json& v, const std::string& path) {
  v_.expect_object(v, path);
  v_.check_keys(v, path, {"width", "height", "size"});
  const int kMax = kMaxImageSide;
  if (const Json* s = v_.find(v, "size")) {
    if (v_.find(v, "width") || v_.find(v, "height"))
      v_.fail(join_key(path, "size"), "give either size or width/height, not both");
    if (!s->is_array() || s->size() != 2)
      v_.fail(join_key(path, "size"), std::string("expected [width, height], not ") + kind(*s));
    scene_.width = v_.integer((*s)[0], join_index(join_key(path, "size"), 0), 1, kMax);
    scene_.height = v_.integer((*s)[1], join_index(join_key(path, "size"), 1), 1, kMax);
  } else {
    scene_.width = v_.integer(v_.require(v, path, "width"), join_key(path, "width"), 1, kMax);
    scene_.height = v_.integer(v_.require(v, path, "height"), join_key(path, "height"), 1, kMax);
  }
  if (static_cast<long long>(scene_.width) * scene_.height > kMaxImagePixels)
    v_.fail(v_.find(v, "size") ? join_key(path, "size") : path, std::to_string(scene_.width) + " x " + std::to_string(scene_.height) +
                   " pixels; at most " + std::to_string(kMaxImagePixels) + " (2^26) are allowed");
}

void SceneSections::camera(const Json& v, const std::string& path) {
  v_.expect_object(v, path);
  v_.check_keys(v, path, {"eye", "look_at", "up", "fov"});
  CameraDesc cam;
  cam.eye = v_.vec3(v_.require(v, path, "eye"), join_key(path, "eye"));
  cam.look_at = v_.vec3(v_.require(v, path, "look_at"), join_key(path, "look_at"));
  if (const Json* u = v_.find(v, "up")) cam.up = v_.vec3(*u, join_key(path, "up"));
  if (const Json* f = v_.find(v, "fov")) {
    cam.fov_deg = v_.real(*f, join_key(path, "fov"));
    if (!(cam.fov_deg > 0 && cam.fov_deg < 180))
      v_.fail(join_key(path, "fov"), "must be between 0 and 180 degrees (exclusive), not " +
                                      num_text(cam.fov_deg));
  }
  double f[3], u[3];
  for (int a = 0; a < 3; ++a) {
    f[a] = double(cam.look_at[a]) - double(cam.eye[a]);
    u[a] = cam.up[a];
  }
  const double fl = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  const double ul = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  if (!(fl > 0)) v_.fail(join_key(path, "look_at"), "is the same point as the eye");
  const double c[3] = {f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2],
                       f[0] * u[1] - f[1] * u[0]};
  const double cl = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  if (!(cl > 1e-6 * fl * ul) || !std::isfinite(cl))
    v_.fail(join_key(path, "up"), "is zero or parallel to the viewing direction");
  scene_.camera = cam;
  scene_.has_camera = true;
  scene_.camera_where = v_.place(path);
  scene_.camera_up_where = v_.find(v, "up") ? v_.place(join_key(path, "up")) : "";  // "": the default up
}

void SceneSections::lights(const Json& v, const std::string& path) {
  v_.expect_array(v, path);
  if (v.size() > OPSILA_MAX_LIGHTS)
    v_.fail(path, std::to_string(v.size()) + " lights; at most " +
                   std::to_string(OPSILA_MAX_LIGHTS) + " are supported");
  for (std::size_t i = 0; i < v.size(); ++i) {
    const std::string p = join_index(path, i);
    v_.expect_object(v[i], p);
    v_.check_keys(v[i], p, {"position", "intensity"});
    LightDesc light;
    light.position = v_.vec3(v_.require(v[i], p, "position"), join_key(p, "position"));
    if (const Json* in = v_.find(v[i], "intensity"))
      light.intensity = v_.colour(*in, join_key(p, "intensity"));
    scene_.lights.push_back(light);
  }
  scene_.has_lights = true;
}

void SceneSections::materials(const Json& v, const std::string& path) {
  v_.expect_object(v, path);
  for (auto it = v.begin(); it != v.end(); ++it) {
    if (it.key() == "comment") continue;  // as in every object (scenes/FORMAT.md): not a material's name
    const std::string p = join_key(path, it.key());
    if (it.key().empty()) v_.fail(p, "a material needs a non-empty name");
    check_material_count(scene_.materials.size() + 1, v_.where(p));
    named_.emplace(it.key(), static_cast<int>(scene_.materials.size()));
    named_order_.push_back(it.key());
    scene_.materials.push_back(material(it.value(), p, it.key()));
  }
}

// CONTRACT terms, plus kr (-> Ks) and kt (-> Tf) with illum chosen to apply them.
MaterialDesc SceneSections::material(const Json& v, const std::string& path, const std::string& name) {
  v_.expect_object(v, path);
  v_.check_keys(v, path, {"Ka", "Kd", "Ks", "Ns", "Ni", "Tf", "illum", "kr", "kt"});
  MaterialDesc m;  // CONTRACT defaults for keys left out
  m.name = name;
  const auto key = [&](const char* k) { return join_key(path, k); };
  if (const Json* x = v_.find(v, "Ka")) m.ka = v_.colour(*x, key("Ka"));
  if (const Json* x = v_.find(v, "Kd")) m.kd = v_.colour(*x, key("Kd"));
  if (const Json* x = v_.find(v, "Ks")) m.ks = v_.colour(*x, key("Ks"));
  if (const Json* x = v_.find(v, "Tf")) m.tf = v_.colour(*x, key("Tf"));
  if (const Json* x = v_.find(v, "Ns")) {
    m.ns = v_.real(*x, key("Ns"));
    if (const std::string why = material_value_problem("Ns", m.ns); !why.empty())
      v_.fail(key("Ns"), why);
  }
  if (const Json* x = v_.find(v, "Ni")) m.ni = v_.positive(*x, key("Ni"));
  const Json* kr = v_.find(v, "kr");
  const Json* kt = v_.find(v, "kt");
  if (kr) {
    if (v_.find(v, "Ks")) v_.fail(key("kr"), "give either Ks or kr, not both (kr sets Ks)");
    m.ks = v_.colour(*kr, key("kr"));
  }
  if (kt) {
    if (v_.find(v, "Tf")) v_.fail(key("kt"), "give either Tf or kt, not both (kt sets Tf)");
    m.tf = v_.colour(*kt, key("kt"));
  }
  if (const Json* x = v_.find(v, "illum")) {
    m.illum = v_.integer(*x, key("illum"), 0, 10);
    if (kr && !illum_reflects(m.illum))
      v_.fail(key("kr"), "has no effect with illum " + std::to_string(m.illum) +
                          " (reflection needs illum 3..7)");
    if (kt && !illum_transmits(m.illum))
      v_.fail(key("kt"), "has no effect with illum " + std::to_string(m.illum) +
                          " (transmission needs illum 4, 6 or 7)");
  } else {
    m.illum = kt ? 6 : kr ? 3 : 0;
  }
  return m;
}

int SceneSections::material_ref(const Json* v, const std::string& path) {
  if (!v) return 0;
  if (v->is_string()) {
    const std::string n = v->get<std::string>();
    auto it = named_.find(n);
    if (it == named_.end()) {
      // As in OBJ (FORMAT.md): a warning, and the default material.
      std::string known;
      for (const std::string& k : named_order_) {
        known += (known.empty() ? "" : ", ") + quoted_prefix(k);
        if (known.size() > 200) {
          known += ", ...";
          break;
        }
      }
      v_.warn(path, "unknown material '" + quoted_prefix(n) + "'" +
                     (known.empty() ? " (the scene defines none)" : " (defined: " + known + ")") +
                     "; the default material is used");
      return 0;
    }
    return it->second;
  }
  if (v->is_object()) {
    check_material_count(scene_.materials.size() + 1, v_.where(path));
    scene_.materials.push_back(material(*v, path, path));
    return static_cast<int>(scene_.materials.size()) - 1;
  }
  v_.fail(path, std::string("expected a material name or an inline material, not ") + kind(*v));
}

std::vector<int> SceneSections::material_list(const Json& v, const std::string& path) {
  v_.expect_array(v, path);
  if (v.empty()) v_.fail(path, "needs at least one material");
  std::vector<int> out;
  for (std::size_t i = 0; i < v.size(); ++i)
    out.push_back(material_ref(&v[i], join_index(path, i)));
  return out;
}

Transform SceneSections::transform(const Json& v, const std::string& path) {
  v_.expect_object(v, path);
  v_.check_keys(v, path, {"translate", "rotate", "scale"});
  Transform t;
  if (const Json* x = v_.find(v, "translate")) t.translate = v_.vec3(*x, join_key(path, "translate"));
  if (const Json* x = v_.find(v, "rotate")) t.rotate_deg = v_.vec3(*x, join_key(path, "rotate"));
  if (const Json* x = v_.find(v, "scale")) {
    const std::string p = join_key(path, "scale");
    if (x->is_number()) {
      const float s = v_.positive(*x, p);
      t.scale = {s, s, s};
    } else if (x->is_array() && x->size() == 3) {
      for (int a = 0; a < 3; ++a) t.scale[a] = v_.positive((*x)[a], join_index(p, a));
    } else {
      v_.fail(p, std::string("expected a positive number or [x, y, z], not ") + kind(*x));
    }
  }
  return t;
}

}  // namespace scene_json
}  // namespace opsila
