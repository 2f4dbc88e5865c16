// What an STL file is, as the importer reads it: binary (an 80-byte
// header, a little-endian uint32 facet count, then 50 bytes a facet: a
// float32 normal, three float32 corners, a uint16 attribute) or ASCII
// ("solid ... facet normal ... vertex ... endfacet ... endsolid"). One home
// for the checks before the importer (stl_checks.cpp), the stream's
// refusals (stl_window.cpp) and the check of the importer's STL scene.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

struct aiScene;

namespace opsila {
namespace stl {

constexpr std::uint64_t kHeaderBytes = 84;  // 80 bytes of text, the facet count
constexpr std::uint64_t kRecordBytes = 50;  // a facet of a binary file
// The bytes of a file that its shape is told from (the header and a few
// more: the importer's search for colours may run past the 80 bytes).
constexpr std::size_t kShapeBytes = kHeaderBytes + 16;

// What a file's first bytes say it is. The importer takes a file as binary
// exactly when its size is 84 + 50 x the header's count (whatever its first
// bytes), else as text when it starts with "solid" (after white space),
// else as binary; it reads a header naming "COLOR=" or "MATERIAL=" as
// Materialise's, with colours.
struct Shape {
  std::uint64_t size = 0;
  std::uint64_t facets = 0;  // the binary header's count (0 for a file shorter than the header)
  bool exact = false;        // size is 84 + 50 x facets
  bool solid = false;        // starts with "solid"
  bool solid_cased = false;  // starts with "solid" in another case ("SOLID"): text the importer does not read
  std::string colours;       // "COLOR=" or "MATERIAL=", where the header names it; else ""
  bool text() const { return solid && !exact; }
};
// `head`: the first kShapeBytes bytes of a file of `size` bytes (or more).
Shape shape_of(const std::string& head, std::uint64_t size);

// Why the STL stream does not read a file of this shape exactly as the
// importer does, "" when it does: text, a size other than the count's, no
// facets, Materialise colours.
std::string stream_refusal(const Shape& s);

// The checks before the importer reads the STL file `bytes` (named `name`):
// a binary file holds the facets its header counts; a text file ends every
// facet and solid it opens, and its 'vertex' and 'normal' values are
// numbers (vertices finite in floats).
void check_stl(const std::string& bytes, const std::string& name);

// The importer's scene of an STL file, checked as its validation step
// would: the importer reads STL without that step (it refuses a mesh
// without vertices, and a text STL makes one of every solid, so one empty
// solid beside a full one refused the whole file). An empty solid keeps
// its mesh's place, hence the object ids of the solids after it.
void check_imported_scene(const aiScene& ai, const std::string& name);

}  // namespace stl
}  // namespace opsila
