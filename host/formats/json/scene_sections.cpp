// The scene sections of the JSON scene format (scenes/FORMAT.md): image,
// camera, lights, materials and transforms.
#include "formats/json/scene_reader.h"

namespace opsila {

namespace fs = std::filesystem;

namespace scene_json {

// ----------------------------------------------------------- sections ---
void SceneReader::image(const Json& v, const std::string& path) {
  expect_object(v, path);
  check_keys(v, path, {"width", "height", "size"});
  const int kMax = kMaxImageSide;
  if (const Json* s = find(v, "size")) {
    if (find(v, "width") || find(v, "height"))
      fail(join_key(path, "size"), "give either size or width/height, not both");
    if (!s->is_array() || s->size() != 2)
      fail(join_key(path, "size"), std::string("expected [width, height], not ") + kind(*s));
    scene_.width = integer((*s)[0], join_index(join_key(path, "size"), 0), 1, kMax);
    scene_.height = integer((*s)[1], join_index(join_key(path, "size"), 1), 1, kMax);
  } else {
    scene_.width = integer(require(v, path, "width"), join_key(path, "width"), 1, kMax);
    scene_.height = integer(require(v, path, "height"), join_key(path, "height"), 1, kMax);
  }
  if (static_cast<long long>(scene_.width) * scene_.height > kMaxImagePixels)
    fail(find(v, "size") ? join_key(path, "size") : path, std::to_string(scene_.width) + " x " + std::to_string(scene_.height) +
                   " pixels; at most " + std::to_string(kMaxImagePixels) + " (2^26) are allowed");
}

void SceneReader::camera(const Json& v, const std::string& path) {
  expect_object(v, path);
  check_keys(v, path, {"eye", "look_at", "up", "fov"});
  CameraDesc cam;
  cam.eye = vec3(require(v, path, "eye"), join_key(path, "eye"));
  cam.look_at = vec3(require(v, path, "look_at"), join_key(path, "look_at"));
  if (const Json* u = find(v, "up")) cam.up = vec3(*u, join_key(path, "up"));
  if (const Json* f = find(v, "fov")) {
    cam.fov_deg = real(*f, join_key(path, "fov"));
    if (!(cam.fov_deg > 0 && cam.fov_deg < 180))
      fail(join_key(path, "fov"), "must be between 0 and 180 degrees (exclusive), not " +
                                      num_text(cam.fov_deg));
  }
  double f[3], u[3];
  for (int a = 0; a < 3; ++a) {
    f[a] = double(cam.look_at[a]) - double(cam.eye[a]);
    u[a] = cam.up[a];
  }
  const double fl = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  const double ul = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  if (!(fl > 0)) fail(join_key(path, "look_at"), "is the same point as the eye");
  const double c[3] = {f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2],
                       f[0] * u[1] - f[1] * u[0]};
  const double cl = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  if (!(cl > 1e-6 * fl * ul) || !std::isfinite(cl))
    fail(join_key(path, "up"), "is zero or parallel to the viewing direction");
  scene_.camera = cam;
  scene_.has_camera = true;
}

void SceneReader::lights(const Json& v, const std::string& path) {
  expect_array(v, path);
  if (v.size() > OPSILA_MAX_LIGHTS)
    fail(path, std::to_string(v.size()) + " lights; at most " +
                   std::to_string(OPSILA_MAX_LIGHTS) + " are supported");
  for (std::size_t i = 0; i < v.size(); ++i) {
    const std::string p = join_index(path, i);
    expect_object(v[i], p);
    check_keys(v[i], p, {"position", "intensity"});
    LightDesc light;
    light.position = vec3(require(v[i], p, "position"), join_key(p, "position"));
    if (const Json* in = find(v[i], "intensity"))
      light.intensity = colour(*in, join_key(p, "intensity"));
    scene_.lights.push_back(light);
  }
  scene_.has_lights = true;
}

void SceneReader::materials(const Json& v, const std::string& path) {
  expect_object(v, path);
  for (auto it = v.begin(); it != v.end(); ++it) {
    const std::string p = join_key(path, it.key());
    if (it.key().empty()) fail(p, "a material needs a non-empty name");
    named_.emplace(it.key(), static_cast<int>(scene_.materials.size()));
    named_order_.push_back(it.key());
    scene_.materials.push_back(material(it.value(), p, it.key()));
  }
}

// SPEC terms, plus kr (-> Ks) and kt (-> Tf) with illum chosen to apply them.
MaterialDesc SceneReader::material(const Json& v, const std::string& path, const std::string& name) {
  expect_object(v, path);
  check_keys(v, path, {"Ka", "Kd", "Ks", "Ns", "Ni", "Tf", "illum", "kr", "kt"});
  MaterialDesc m;  // SPEC defaults for keys left out
  m.name = name;
  const auto key = [&](const char* k) { return join_key(path, k); };
  if (const Json* x = find(v, "Ka")) m.ka = colour(*x, key("Ka"));
  if (const Json* x = find(v, "Kd")) m.kd = colour(*x, key("Kd"));
  if (const Json* x = find(v, "Ks")) m.ks = colour(*x, key("Ks"));
  if (const Json* x = find(v, "Tf")) m.tf = colour(*x, key("Tf"));
  if (const Json* x = find(v, "Ns")) {
    m.ns = real(*x, key("Ns"));
    if (const std::string why = material_value_problem("Ns", m.ns); !why.empty())
      fail(key("Ns"), why);
  }
  if (const Json* x = find(v, "Ni")) m.ni = positive(*x, key("Ni"));
  const Json* kr = find(v, "kr");
  const Json* kt = find(v, "kt");
  if (kr) {
    if (find(v, "Ks")) fail(key("kr"), "give either Ks or kr, not both (kr sets Ks)");
    m.ks = colour(*kr, key("kr"));
  }
  if (kt) {
    if (find(v, "Tf")) fail(key("kt"), "give either Tf or kt, not both (kt sets Tf)");
    m.tf = colour(*kt, key("kt"));
  }
  if (const Json* x = find(v, "illum")) {
    m.illum = integer(*x, key("illum"), 0, 10);
    if (kr && !illum_reflects(m.illum))
      fail(key("kr"), "has no effect with illum " + std::to_string(m.illum) +
                          " (reflection needs illum 3..7)");
    if (kt && !illum_transmits(m.illum))
      fail(key("kt"), "has no effect with illum " + std::to_string(m.illum) +
                          " (transmission needs illum 4, 6 or 7)");
  } else {
    m.illum = kt ? 6 : kr ? 3 : 0;
  }
  return m;
}

// A material name from "materials", or an inline material; none = default.
int SceneReader::material_ref(const Json* v, const std::string& path) {
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
      warn(path, "unknown material '" + quoted_prefix(n) + "'" +
                     (known.empty() ? " (the scene defines none)" : " (defined: " + known + ")") +
                     "; the default material is used");
      return 0;
    }
    return it->second;
  }
  if (v->is_object()) {
    scene_.materials.push_back(material(*v, path, path));
    return static_cast<int>(scene_.materials.size()) - 1;
  }
  fail(path, std::string("expected a material name or an inline material, not ") + kind(*v));
}

std::vector<int> SceneReader::material_list(const Json& v, const std::string& path) {
  expect_array(v, path);
  if (v.empty()) fail(path, "needs at least one material");
  std::vector<int> out;
  for (std::size_t i = 0; i < v.size(); ++i)
    out.push_back(material_ref(&v[i], join_index(path, i)));
  return out;
}

Transform SceneReader::transform(const Json& v, const std::string& path) {
  expect_object(v, path);
  check_keys(v, path, {"translate", "rotate", "scale"});
  Transform t;
  if (const Json* x = find(v, "translate")) t.translate = vec3(*x, join_key(path, "translate"));
  if (const Json* x = find(v, "rotate")) t.rotate_deg = vec3(*x, join_key(path, "rotate"));
  if (const Json* x = find(v, "scale")) {
    const std::string p = join_key(path, "scale");
    if (x->is_number()) {
      const float s = positive(*x, p);
      t.scale = {s, s, s};
    } else if (x->is_array() && x->size() == 3) {
      for (int a = 0; a < 3; ++a) t.scale[a] = positive((*x)[a], join_index(p, a));
    } else {
      fail(p, std::string("expected a positive number or [x, y, z], not ") + kind(*x));
    }
  }
  return t;
}

}  // namespace scene_json
}  // namespace opsila
