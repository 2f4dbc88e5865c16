// One rank's window of a binary STL (stl_format.h) read as a stream
// (model_window.h). The records are read in blocks (64 Ki records at most) into a mesh of the
// block's corners, each corner with its facet's normal, as the importer's
// STL reader makes the whole file's mesh, and fanned by WindowFan
// (model_fan.h): a facet is kept only when it falls in this rank's slice of
// the plan; the others are only counted into the whole file's figures, so
// counts, warnings and errors are one process's on every rank. The
// attribute (a colour to some writers) is read and let go: the importer
// path keeps no vertex colour.
#include "formats/stl/stl_reader.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <vector>

#include "core/errors.h"
#include "formats/common/model_files.h"
#include "formats/stl/stl_format.h"

#ifdef OPSILA_HAVE_ASSIMP
#include <assimp/mesh.h>

#include "formats/common/model_fan.h"
#endif

namespace opsila {

#ifdef OPSILA_HAVE_ASSIMP

namespace {

constexpr std::uint64_t kBlockRecords = std::uint64_t(1) << 16;

std::uint32_t le32(const unsigned char* b) {
  return std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24;
}

// The file's facet count, or why the stream leaves the file to the
// importer (stl_format.h), or a file that cannot be read (the importer path
// then judges it, with its own message).
std::string refusal(const std::string& path, std::uint64_t& count) {
  std::uint64_t size = 0;
  std::string head;
  try {
    ModelFiles files;
    size = files.size(path);
    head = files.head(path, stl::kShapeBytes);
  } catch (const InputError& e) {
    return std::string("its size: ") + e.what();
  }
  const stl::Shape shape = stl::shape_of(head, size);
  count = shape.facets;
  return stl::stream_refusal(shape);
}

float le_float(const unsigned char* b) {
  const std::uint32_t bits = le32(b);
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

aiVector3D le_vector(const unsigned char* b) { return aiVector3D(le_float(b), le_float(b + 4), le_float(b + 8)); }

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

Scene read_window(const std::string& path, std::size_t max_triangles, const ModelWindow& window, std::uint64_t& fans,
                  std::size_t block_bytes) {
  std::uint64_t count = 0;
  const std::string why = refusal(path, count);
  if (!why.empty()) throw InputError(path + ": the STL stream cannot read this file: " + why);
  const std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file || std::fseek(file.get(), long(stl::kHeaderBytes), SEEK_SET) != 0)
    throw InputError(path + ": cannot read: " + std::strerror(errno));
  // A block of records, and the mesh of its corners (the importer's, for
  // these facets: corner 3j + c of record j, each with the record's normal):
  // 122 bytes a record, so at most kBlockRecords of them (8 MB).
  const std::size_t block = static_cast<std::size_t>(std::min<std::uint64_t>(
      {count, std::max<std::size_t>(block_bytes / stl::kRecordBytes, 1), kBlockRecords}));
  std::vector<unsigned char> bytes(block * stl::kRecordBytes);
  aiMesh mesh;
  mesh.mNumVertices = static_cast<unsigned>(3 * block);
  mesh.mVertices = new aiVector3D[3 * block];
  mesh.mNormals = new aiVector3D[3 * block];
  Scene scene;
  WindowFan fan(path, mesh, max_triangles, window, scene);
  for (std::uint64_t first = 0; first < count; first += block) {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(block, count - first));
    const std::size_t got = std::fread(bytes.data(), 1, n * stl::kRecordBytes, file.get());
    if (got < n * stl::kRecordBytes)  // shorter than when its size was read: it changed
      throw InputError(path + ": STL facet " + std::to_string(first + got / stl::kRecordBytes + 1) + " of " +
                       std::to_string(count) + " at byte " +
                       std::to_string(stl::kHeaderBytes + first * stl::kRecordBytes + got) +
                       ": the file ends early (truncated)");
    for (std::size_t j = 0; j < n; ++j) {
      const unsigned char* r = bytes.data() + j * stl::kRecordBytes;
      const aiVector3D normal = le_vector(r);
      const unsigned corner[3] = {unsigned(3 * j), unsigned(3 * j + 1), unsigned(3 * j + 2)};
      for (int c = 0; c < 3; ++c) {
        mesh.mNormals[corner[c]] = normal;
        mesh.mVertices[corner[c]] = le_vector(r + 12 + 12 * c);
      }
      fan.face(corner, 3, static_cast<unsigned>(first + j));
    }
  }
  fan.finish(fans);
  return scene;
}

}  // namespace

std::string stl_stream_refusal(const std::string& path) {
  std::uint64_t count = 0;
  return refusal(path, count);
}

Scene load_stl_window(const std::string& path, std::size_t max_triangles, const ModelWindow& window,
                      std::uint64_t& fans, std::size_t block_bytes) {
  try {
    return read_window(path, max_triangles, window, fans, block_bytes);
  } catch (const std::bad_alloc&) {
    throw InputError(path + ": out of memory while loading (model too large)");
  } catch (const std::length_error&) {
    throw InputError(path + ": model too large to load");
  }
}

#else  // built without the Open Asset Import Library: the importer path says so

std::string stl_stream_refusal(const std::string&) { return "this build has no Open Asset Import Library"; }

Scene load_stl_window(const std::string& path, std::size_t, const ModelWindow&, std::uint64_t&, std::size_t) {
  throw InputError(path + ": this build has no Open Asset Import Library (install libassimp-dev and rebuild)");
}

#endif

}  // namespace opsila
