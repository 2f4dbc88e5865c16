// The importer's materials -> CONTRACT's material keys. A material is used as
// the file gives it, whatever its name; only the importer's placeholder for
// "no material" becomes CONTRACT's default material.
#include "formats/assimp/model_materials.h"

#ifdef OPSILA_HAVE_ASSIMP
#include <algorithm>
#include <cmath>
#include <cstdint>

#include <assimp/material.h>
#include <assimp/scene.h>

#include "formats/image/texture_file.h"

namespace opsila {

namespace {

// A colour the material gives: `given` is false when the key is absent (or
// not a finite colour, which no reader means as one).
Vec3 colour(const aiMaterial& m, const char* key, unsigned type, unsigned index, bool& given) {
  aiColor4D c;
  given = aiGetMaterialColor(&m, key, type, index, &c) == AI_SUCCESS && std::isfinite(c.r) &&
          std::isfinite(c.g) && std::isfinite(c.b);
  if (!given) return Vec3{0, 0, 0};
  return Vec3{std::max(0.0f, c.r), std::max(0.0f, c.g), std::max(0.0f, c.b)};
}

bool nonzero(const Vec3& c) { return c[0] != 0 || c[1] != 0 || c[2] != 0; }

// The file the material names for its first map of one kind ("" = none).
std::string map_path(const aiMaterial& m, aiTextureType type) {
  aiString path;
  if (m.GetTexture(type, 0, &path) != AI_SUCCESS) return "";
  return path.C_Str();
}

// The importer's stand-in for "no material" (CONTRACT, other model formats): no
// name or AI_DEFAULT_MATERIAL_NAME (what the STL, PLY, OFF, SMD, MDL, ...
// readers make up), no texture map, and a grey diffuse colour (or none).
// NFF names its coloured materials so too, and HL1 MDL leaves its textured
// ones unnamed: both are used as the file gives them.
bool is_placeholder(const aiMaterial& m) {
  aiString name;
  const bool named = m.Get(AI_MATKEY_NAME, name) == AI_SUCCESS && name.length > 0;
  if (named && std::string(name.C_Str()) != AI_DEFAULT_MATERIAL_NAME) return false;
  if (!map_path(m, aiTextureType_DIFFUSE).empty() || !map_path(m, aiTextureType_AMBIENT).empty()) return false;
  bool given = false;
  const Vec3 kd = colour(m, AI_MATKEY_COLOR_DIFFUSE, given);
  return !given || (kd[0] == kd[1] && kd[1] == kd[2]);
}

class MaterialReader {
 public:
  MaterialReader(const aiScene& ai, const std::string& name, const std::string& base_dir, Scene& scene,
                 MapImages images)
      : ai_(ai), name_(name), base_dir_(base_dir), scene_(scene), images_(images) {}

  std::vector<int> run() {
    std::vector<int> index(ai_.mNumMaterials, 0);
    // glTF 2: the importer appends its stand-in, unnamed, after the file's
    // own materials, which are used as given (an unnamed black one had been
    // taken for the stand-in and drawn in the default grey).
    aiString format;
    const bool gltf2 = ai_.mMetaData && ai_.mMetaData->Get("SourceAsset_Format", format) &&
                       std::string(format.C_Str()) == "glTF2 Importer";
    for (unsigned i = 0; i < ai_.mNumMaterials; ++i) {
      if (gltf2 ? i + 1 == ai_.mNumMaterials : is_placeholder(*ai_.mMaterials[i])) continue;  // stays 0
      check_material_count(scene_.materials.size() + 1, name_ + ": material " + std::to_string(i) + ": ");
      index[i] = static_cast<int>(scene_.materials.size());
      scene_.materials.push_back(material(*ai_.mMaterials[i], i));
    }
    return index;
  }

 private:
  void warn(const std::string& what) { scene_.warnings.push_back(name_ + ": " + what); }

  // CONTRACT keys from the importer's: ambient, diffuse, specular colours,
  // shininess, refraction index, transparent colour and shading model.
  // "Left out" is the key's absence from the material. The readers that
  // make up a material themselves (MD2, MD3, MDC, MDL, HMP, SMD) store a
  // diffuse colour of 1 beside a texture and a grey one without: the first
  // agrees with CONTRACT, the second is the placeholder above. glTF 1, IQM, SMD
  // and HL1 MDL give a texture and no diffuse colour: Kd = 1 (CONTRACT).
  MaterialDesc material(const aiMaterial& am, unsigned i) {
    MaterialDesc m;  // CONTRACT defaults for keys left out
    aiString ainame;
    m.name = am.Get(AI_MATKEY_NAME, ainame) == AI_SUCCESS && ainame.length > 0 ? ainame.C_Str()
                                                                                : "material " + std::to_string(i);
    bool ka_given = false, kd_given = false, unused = false;
    m.ka = colour(am, AI_MATKEY_COLOR_AMBIENT, ka_given);
    m.kd = colour(am, AI_MATKEY_COLOR_DIFFUSE, kd_given);
    m.ks = colour(am, AI_MATKEY_COLOR_SPECULAR, unused);
    m.tf = colour(am, AI_MATKEY_COLOR_TRANSPARENT, unused);
    const std::string kd_map = map_path(am, aiTextureType_DIFFUSE), ka_map = map_path(am, aiTextureType_AMBIENT);
    if (!ka_given) m.ka = left_out_colour(!ka_map.empty());
    if (!kd_given) m.kd = left_out_colour(!kd_map.empty());
    float x = 0;
    if (am.Get(AI_MATKEY_SHININESS, x) == AI_SUCCESS && std::isfinite(x) && x >= 0) m.ns = x;
    if (am.Get(AI_MATKEY_REFRACTI, x) == AI_SUCCESS && std::isfinite(x) && x > 0) m.ni = x;
    float opacity = 1;
    if (am.Get(AI_MATKEY_OPACITY, x) == AI_SUCCESS && std::isfinite(x)) opacity = x;
    int model = 0;
    const bool has_model = am.Get(AI_MATKEY_SHADING_MODEL, model) == AI_SUCCESS;
    // Shading model -> illum: unlit is 0, everything else 2 (highlights);
    // a transparent colour on a material that is not opaque is glass
    // (illum 4: kt = Tf, kr = Ks).
    m.illum = has_model && model == aiShadingMode_NoShading ? 0 : 2;
    if (nonzero(m.tf) && opacity < 1.0f) m.illum = 4;
    m.map_kd = texture(kd_map, i);
    m.map_ka = texture(ka_map, i);
    return m;
  }

  // A material's map, read when some mesh that uses the material has
  // texture coordinates (others could not show it).
  int texture(const std::string& path, unsigned material) {
    if (path.empty()) return -1;
    bool needed = false;
    for (unsigned m = 0; m < ai_.mNumMeshes && !needed; ++m)
      needed = ai_.mMeshes[m]->mMaterialIndex == material && ai_.mMeshes[m]->HasTextureCoords(0);
    if (!needed) return -1;
    if (const aiTexture* embedded = ai_.GetEmbeddedTexture(path.c_str())) return embedded_texture(*embedded, path);
    if (base_dir_.empty()) {
      warn("texture map '" + path + "' ignored: no files are read here");
      return -1;
    }
    return add_texture_file(scene_, resolve_texture_path(path, base_dir_), name_ + ": ", images_);
  }

  int embedded_texture(const aiTexture& t, const std::string& ref) {
    const std::string key = name_ + "#" + ref;
    for (std::size_t i = 0; i < scene_.textures.size(); ++i)
      if (scene_.textures[i].path == key) return static_cast<int>(i);
    Texture out;
    std::string problem;
    bool ok = false;
    if (t.mHeight == 0) {  // compressed: mWidth bytes of PNG, JPEG, ...
      ok = decode_texture_memory(reinterpret_cast<const unsigned char*>(t.pcData), t.mWidth, key, out, problem);
    } else if (t.mWidth <= unsigned(kMaxTextureSide) && t.mHeight <= unsigned(kMaxTextureSide)) {
      out.path = key;
      out.width = static_cast<int>(t.mWidth);
      out.height = static_cast<int>(t.mHeight);
      out.texels.resize(std::size_t(t.mWidth) * t.mHeight);
      for (std::size_t i = 0; i < out.texels.size(); ++i)
        out.texels[i] = std::uint32_t(t.pcData[i].r) | std::uint32_t(t.pcData[i].g) << 8 |
                        std::uint32_t(t.pcData[i].b) << 16;
      ok = true;
    } else {
      problem = "image too large";
    }
    if (!ok) {
      warn("embedded texture map '" + ref + "' ignored: " + problem);
      return -1;
    }
    scene_.textures.push_back(std::move(out));
    return static_cast<int>(scene_.textures.size()) - 1;
  }

  const aiScene& ai_;
  const std::string& name_;
  const std::string& base_dir_;
  Scene& scene_;
  MapImages images_;
};

}  // namespace

std::vector<int> import_materials(const aiScene& ai, const std::string& name, const std::string& base_dir,
                                  Scene& scene, MapImages images) {
  return MaterialReader(ai, name, base_dir, scene, images).run();
}

}  // namespace opsila

#endif  // OPSILA_HAVE_ASSIMP
