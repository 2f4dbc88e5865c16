// A mesh's faces fanned into CONTRACT triangles as the importer path makes
// them: from the first corner, every fan triangle with the face's id,
// positions by the node transform (a mirroring one turns each triangle's
// winding, so Ng stays outward), normals by its inverse transpose; a
// zero-area triangle is dropped (and counted), a corner that is not a finite
// number or a triangle whose edges overflow float refuses the file. One
// home for the importer's meshes (model_import.cpp) and the PLY
// and STL streams (ply_window.cpp, stl_window.cpp), so they all give the
// same triangles bit for bit.
#pragma once

#ifdef OPSILA_HAVE_ASSIMP
#include <climits>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <assimp/matrix3x3.h>
#include <assimp/matrix4x4.h>
#include <assimp/mesh.h>

#include "scene/scene.h"
#include "formats/common/window.h"

namespace opsila {

// What the fanned faces of a model add up to, over all its meshes.
struct FanTally {
  std::uint64_t triangles = 0;  // kept (not zero-area)
  long long degenerate = 0;     // zero-area fan triangles dropped
  Vec3 lo = splat(std::numeric_limits<float>::infinity()), hi = splat(-std::numeric_limits<float>::infinity());
};

class MeshFan {
 public:
  // At most max_triangles triangles over the tally (the model's limit).
  MeshFan(const std::string& name, const aiMesh& mesh, const aiMatrix4x4& place, std::size_t max_triangles,
          FanTally& tally);
  // Face f of mesh `object` (n corners): its triangles are counted into the
  // tally and, when `out` is not null, appended to it with their
  // attributes. True when the face left a triangle.
  bool face(const unsigned* corner, unsigned n, unsigned f, int object, int facet, int material, Scene* out);
  // Which placement of the mesh this is, 0 first: the placements share the
  // mesh's ids, so a facet's triangles are ranked placement by placement,
  // then along the fan (Triangle::fan, the hit order's last key).
  int placement = 0;

 private:
  int attributes(const unsigned* corner, Scene& out) const;

  const std::string& name_;
  const aiMesh& mesh_;
  aiMatrix4x4 place_;
  aiMatrix3x3 normal_matrix_;
  bool mirrored_ = false;  // the placement's determinant is negative
  std::size_t max_triangles_;
  FanTally& tally_;
};

// A model file of one mesh read as a stream by one rank of several (the
// PLY and STL streams): its faces, in file order, are fanned into the whole
// file's figures and kept only when their first fan triangle falls in the
// rank's window (window_owner, the OBJ stream's rule). The scene is the
// importer path's (model_import.cpp) for a file of one unplaced-free mesh
// with the "no material" default material: one object, facet ids counted
// over the faces of 3 corners or more, the same warnings and errors.
class WindowFan {
 public:
  // `mesh` holds the vertices the faces name (it may be refilled between
  // faces); `scene` gets the window's triangles.
  WindowFan(const std::string& path, const aiMesh& mesh, std::size_t max_triangles, const ModelWindow& window,
            Scene& scene);
  // Face f of the file, of n >= 3 corners of the mesh's vertices.
  void face(const unsigned* corner, unsigned n, unsigned f);
  // A face of fewer than 3 corners: no facet, no id.
  void skip() { ++skipped_; }
  // The importer path's ending on the whole file's figures (warnings, no
  // facets, extent, camera) and the window's share of them; `fans` gets the
  // file's fan triangles.
  void finish(std::uint64_t& fans);

 private:
  const std::string& path_;
  ModelWindow window_;
  Scene& scene_;
  FanTally tally_;
  MeshFan fan_;
  std::uint64_t fans_ = 0;
  int facets_ = 0;
  long long skipped_ = 0;
  int lowest_ = INT_MAX, highest_ = -1;  // the ranks holding a triangle
};

// The importer path's warnings about a model's faces, in its order.
std::vector<std::string> fan_warnings(const std::string& name, long long skipped, int unplaced,
                                      long long degenerate);

}  // namespace opsila
#endif
