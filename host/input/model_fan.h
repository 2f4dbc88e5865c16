// A mesh's faces fanned into SPEC triangles as the importer path makes
// them: from the first corner, every fan triangle with the face's id,
// positions by the node transform, normals by its inverse transpose; a
// zero-area triangle is dropped (and counted), a corner that is not a finite
// number or a triangle whose edges overflow float refuses the file. One
// home for the importer's meshes (model_import.cpp) and the PLY stream
// (ply_window.cpp), so both give the same triangles bit for bit.
#pragma once

#ifdef OPSILA_HAVE_ASSIMP
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <assimp/matrix3x3.h>
#include <assimp/matrix4x4.h>
#include <assimp/mesh.h>

#include "core/scene.h"

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

 private:
  int attributes(const unsigned* corner, Scene& out) const;

  const std::string& name_;
  const aiMesh& mesh_;
  aiMatrix4x4 place_;
  aiMatrix3x3 normal_matrix_;
  std::size_t max_triangles_;
  FanTally& tally_;
};

// The importer path's warnings about a model's faces, in its order.
std::vector<std::string> fan_warnings(const std::string& name, long long skipped, int unplaced,
                                      long long degenerate);

}  // namespace opsila
#endif
