// One rank's window of a PLY model read as a stream (ply_reader.h): the
// vertex element is read whole, the face element face after face, each
// face fanned as the importer path fans it (model_fan.h) and kept only
// when its first fan triangle falls in this rank's slice of the plan
// (window_owner, the OBJ stream's rule); the others are only counted into
// the whole file's figures, so counts, warnings and errors are one
// process's on every rank.
#include "formats/ply/ply_reader.h"

#ifdef OPSILA_HAVE_ASSIMP
#include <algorithm>
#include <climits>
#include <cmath>
#include <new>
#include <string>
#include <unordered_map>

#include <assimp/mesh.h>

#include "formats/common/model_fan.h"
#include "formats/ply/ply_format.h"

namespace opsila {

namespace {

// The vertex arrays the importer path uses: positions, normals (nx, ny,
// nz) and the first texture coordinates ((u, v), (s, t), ...), as floats.
// not_finite: the line of each vertex whose position is not finite in
// floats, in a text file (named if a face uses it, as the importer path's
// checks name it; in a binary file both paths name the mesh and face).
void read_vertices(ply::Body& body, const ply::Element& e, const ply::Header& h, aiMesh& mesh, const std::string& path,
                   std::unordered_map<unsigned, std::string>& not_finite) {
  // Each vertex takes at least a byte a value: a count the file cannot
  // hold is refused before anything is allocated.
  const std::uint64_t per = h.format == ply::Format::ascii ? 2 * e.properties.size() - 1 : e.properties.size();
  if (e.count > (h.file_bytes - h.body) / std::max<std::uint64_t>(per, 1) || e.count > UINT_MAX)
    throw InputError(path + ":" + std::to_string(e.line) + ": PLY header asks for " + std::to_string(e.count) +
                     " vertices, more than the file's " + std::to_string(h.file_bytes) + " bytes can hold");
  enum Role { none, px, py, pz, nx, ny, nz, tu, tv };
  std::vector<Role> role;
  bool normals = false, uvs = false;
  for (const ply::Property& p : e.properties) {
    const std::string& n = p.name;
    Role r = n == "x" ? px : n == "y" ? py : n == "z" ? pz : n == "nx" ? nx : n == "ny" ? ny : n == "nz" ? nz : none;
    if (n == "u" || n == "s" || n == "texture_u" || n == "texture_s") r = tu;
    if (n == "v" || n == "t" || n == "texture_v" || n == "texture_t") r = tv;
    normals = normals || r == nx, uvs = uvs || r == tu;
    role.push_back(r);
  }
  const unsigned count = static_cast<unsigned>(e.count);
  const bool text = h.format == ply::Format::ascii;
  mesh.mNumVertices = count;
  mesh.mVertices = new aiVector3D[count];
  if (normals) mesh.mNormals = new aiVector3D[count];
  if (uvs) mesh.mTextureCoords[0] = new aiVector3D[count], mesh.mNumUVComponents[0] = 2;
  for (unsigned i = 0; i < count; ++i) {
    for (std::size_t k = 0; k < role.size(); ++k) {
      const float f = body.next(e.properties[k].type, e, i).as_float();
      if (text && (role[k] == px || role[k] == py || role[k] == pz) && !std::isfinite(f))
        not_finite.emplace(i, body.where());
      switch (role[k]) {
        case px: mesh.mVertices[i].x = f; break;
        case py: mesh.mVertices[i].y = f; break;
        case pz: mesh.mVertices[i].z = f; break;
        case nx: mesh.mNormals[i].x = f; break;
        case ny: mesh.mNormals[i].y = f; break;
        case nz: mesh.mNormals[i].z = f; break;
        case tu: mesh.mTextureCoords[0][i].x = f; break;
        case tv: mesh.mTextureCoords[0][i].y = f; break;
        default: break;
      }
    }
    body.end_of_instance(e, i);
  }
}


class PlyWindowReader {
 public:
  PlyWindowReader(const std::string& path, std::size_t max_triangles, const ModelWindow& window, std::size_t block,
                  const std::string* bytes = nullptr)
      : path_(path), bytes_(bytes), max_triangles_(max_triangles), window_(window), block_(block) {}

  Scene run(std::uint64_t& fans) {
    try {
      const ply::Header h = ply::read_header(path_, bytes_);
      const std::string why = ply::stream_refusal(h);
      if (!why.empty()) throw InputError(path_ + ": the PLY stream cannot read this file: " + why);
      ply::Body body(path_, h, block_, bytes_);
      aiMesh mesh;
      std::unordered_map<unsigned, std::string> not_finite;
      read_vertices(body, h.elements[0], h, mesh, path_, not_finite);
      Scene scene;
      WindowFan fan(path_, mesh, max_triangles_, window_, scene);
      vertices_ = mesh.mNumVertices;
      for (std::size_t k = 1; k < h.elements.size(); ++k) {
        if (h.elements[k].name == "face") read_faces(body, h.elements[k], not_finite, fan);
        else read_strips(body, h.elements[k], not_finite, fan);
      }
      body.end_of_data(h.elements.back());
      fan.finish(fans);
      return scene;
    } catch (const std::bad_alloc&) {
      throw InputError(path_ + ": out of memory while loading (model too large)");
    } catch (const std::length_error&) {
      throw InputError(path_ + ": model too large to load");
    }
  }

 private:
  // A face's or strip's vertex index, checked: in range, and its vertex
  // finite where a text file said it is not.
  unsigned corner(ply::Body& body, const ply::Element& e, std::uint64_t f, std::int64_t v,
                  const std::unordered_map<unsigned, std::string>& not_finite) const {
    if (v < 0 || v >= std::int64_t(vertices_))
      body.fail(e, f, "vertex index " + std::to_string(v) + " out of range (the file has " +
                          std::to_string(vertices_) + " vertices)");
    const auto bad = not_finite.find(unsigned(v));
    if (bad != not_finite.end())
      body.fail(e, f, "vertex " + std::to_string(v) + " (" + bad->second + ") is not a finite number");
    return unsigned(v);
  }

  // A list's length, checked.
  unsigned list_length(ply::Body& body, const ply::Element& e, std::uint64_t f, std::uint64_t most) const {
    const ply::Value count = body.next(e.properties[0].count, e, f);
    if (count.i < 0) body.fail(e, f, "a negative number of corners");
    if (std::uint64_t(count.i) > most)
      throw TooManyTriangles(path_ + ": too many triangles (more than " + std::to_string(max_triangles_) + ")");
    return static_cast<unsigned>(count.i);
  }

  // Every face read and checked; fanned into the figures, and into the
  // scene when it is this rank's (WindowFan).
  void read_faces(ply::Body& body, const ply::Element& e,
                  const std::unordered_map<unsigned, std::string>& not_finite, WindowFan& fan) {
    std::vector<unsigned> corners;
    for (std::uint64_t f = 0; f < e.count; ++f) {
      const unsigned n = list_length(body, e, f, max_triangles_ + 2);
      corners.resize(n);
      for (unsigned k = 0; k < n; ++k)
        corners[k] = corner(body, e, f, body.next(e.properties[0].type, e, f).i, not_finite);
      body.end_of_instance(e, f);
      if (n < 3) fan.skip();  // the importer path skips points and lines (and empty faces), with no id
      else fan.face(corners.data(), n, static_cast<unsigned>(f));
    }
    faces_ = e.count;
  }

  // Triangle strips (scenes/FORMAT.md): triangle k of a strip is corners
  // (k, k+1, k+2), every odd one turned (k+1, k, k+2) so that all face the
  // same way; -1 (or a new list) starts a new strip; a triangle naming a
  // vertex twice joins strips and is no facet. Each triangle is a facet of
  // its own, after the faces'.
  void read_strips(ply::Body& body, const ply::Element& e,
                   const std::unordered_map<unsigned, std::string>& not_finite, WindowFan& fan) {
    std::uint64_t triangle = faces_;
    for (std::uint64_t f = 0; f < e.count; ++f) {
      const unsigned n = list_length(body, e, f, UINT_MAX);
      unsigned last[2] = {0, 0};
      std::uint64_t k = 0;  // corners since the strip's start
      for (unsigned c = 0; c < n; ++c) {
        const std::int64_t v = body.next(e.properties[0].type, e, f).i;
        if (v == -1) {
          k = 0;
          continue;
        }
        const unsigned now = corner(body, e, f, v, not_finite);
        if (k >= 2 && last[0] != last[1] && last[1] != now && now != last[0]) {
          const unsigned tri[3] = {k % 2 ? last[1] : last[0], k % 2 ? last[0] : last[1], now};
          fan.face(tri, 3, static_cast<unsigned>(std::min<std::uint64_t>(triangle++, UINT_MAX)));
        }
        last[0] = last[1], last[1] = now, ++k;
      }
      body.end_of_instance(e, f);
    }
  }

  const std::string& path_;
  const std::string* bytes_;  // the file in memory, or nullptr
  std::size_t max_triangles_;
  ModelWindow window_;
  std::size_t block_;
  unsigned vertices_ = 0;
  std::uint64_t faces_ = 0;  // of the 'face' element: the strips' triangles are numbered after them
};

}  // namespace

std::string ply_stream_refusal(const std::string& path) {
  try {
    return ply::stream_refusal(ply::read_header(path));
  } catch (const InputError& e) {  // the importer path judges it, with its own message
    return std::string("its header: ") + e.what();
  }
}

Scene load_ply_window(const std::string& path, std::size_t max_triangles, const ModelWindow& window,
                      std::uint64_t& fans, std::size_t block_bytes) {
  return PlyWindowReader(path, max_triangles, window, block_bytes).run(fans);
}

bool ply_has_strips(const std::string& path, const std::string* bytes) {
  ply::Header h;
  try {
    h = ply::read_header(path, bytes);
  } catch (const InputError&) {
    return false;
  }
  if (!ply::has_strips(h)) return false;
  if (const std::string why = ply::stream_refusal(h); !why.empty())
    throw InputError(path + ": PLY triangle strips are read only from a file of 'vertex', 'face' and 'tristrips' "
                            "elements as scenes/FORMAT.md says, and " + why);
  return true;
}

Scene load_ply_whole(const std::string& path, std::size_t max_triangles, const std::string* bytes) {
  ModelWindow all;  // one rank, one fan triangle in the plan: every face is kept
  all.fans = 1;
  std::uint64_t fans = 0;
  Scene scene = PlyWindowReader(path, max_triangles, all, std::size_t(32) << 20, bytes).run(fans);
  scene.share = SceneShare{};
  return scene;
}

void check_ply_text(const std::string& path, std::size_t max_triangles, const std::string* bytes) {
  ply::Header h;
  try {
    h = ply::read_header(path, bytes);
  } catch (const InputError&) {  // a header only the importer reads: it judges the file
    return;
  }
  if (h.format != ply::Format::ascii || !ply::stream_refusal(h).empty()) return;
  ModelWindow counting;  // no face kept: every value read and checked
  std::uint64_t fans = 0;
  PlyWindowReader(path, max_triangles, counting, std::size_t(32) << 20, bytes).run(fans);
}

std::vector<std::string> ply_unread_elements(const std::string& path) {
  std::vector<std::string> out;
  try {
    for (const ply::Element& e : ply::read_header(path).elements)
      if (e.name != "vertex" && e.name != "face" && e.name != "tristrips" && e.name != "material")
        out.push_back(path + ":" + std::to_string(e.line) + ": the PLY element '" + e.name + "' (" +
                      std::to_string(e.count) + " of them) is not read: only 'vertex', 'face' and 'tristrips' "
                      "give facets, so nothing of it is drawn");
  } catch (const InputError&) {  // a header only the importer reads: it has said what it could
  }
  return out;
}

}  // namespace opsila

#else  // built without the Open Asset Import Library: the importer path says so

namespace opsila {

std::string ply_stream_refusal(const std::string&) { return "this build has no Open Asset Import Library"; }

Scene load_ply_window(const std::string& path, std::size_t, const ModelWindow&, std::uint64_t&, std::size_t) {
  throw InputError(path + ": this build has no Open Asset Import Library (install libassimp-dev and rebuild)");
}

bool ply_has_strips(const std::string&, const std::string*) { return false; }
void check_ply_text(const std::string&, std::size_t, const std::string*) {}
Scene load_ply_whole(const std::string& path, std::size_t, const std::string*) {
  std::uint64_t fans = 0;
  return load_ply_window(path, 0, ModelWindow{}, fans);
}
std::vector<std::string> ply_unread_elements(const std::string&) { return {}; }

}  // namespace opsila

#endif
