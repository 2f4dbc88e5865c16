#include "formats/assimp/import_warnings.h"

#include <cstring>

#include "core/errors.h"
#include "formats/common/model_words.h"

#ifdef OPSILA_HAVE_ASSIMP
#include <assimp/DefaultLogger.hpp>
#include <assimp/LogStream.hpp>
#endif

namespace opsila {

namespace {

// The importer's words (Debian's assimp 5.2) and what they mean here.
struct Dropped {
  const char* said;
  const char* meaning;
};
constexpr Dropped kDropped[] = {
    {"out-of-range indices", "a mesh primitive's indices name vertices past the end of its attributes (the importer "
                             "would drop those faces): every index must be below the POSITION accessor's count"},
    {"not compatible with the TRIANGLES mode", "a triangles primitive's vertex or index count is not a multiple of 3 "
                                               "(the importer would drop the rest)"},
    {"3DS: Vertex index overflow", "a 3DS face names a vertex past its mesh's vertex list (the importer would put "
                                   "the mesh's last vertex in its place)"},
};

}  // namespace

struct ImportWarnings::Heard {
  const Dropped* first = nullptr;
};

#ifdef OPSILA_HAVE_ASSIMP
namespace {

// Owned by the logger once attached; writes into the Heard it shares.
class Listener : public Assimp::LogStream {
 public:
  explicit Listener(std::shared_ptr<ImportWarnings::Heard> heard) : heard_(std::move(heard)) {}
  void write(const char* message) override {
    if (heard_->first) return;
    for (const Dropped& d : kDropped)
      if (std::strstr(message, d.said)) heard_->first = &d;
  }

 private:
  std::shared_ptr<ImportWarnings::Heard> heard_;
};

}  // namespace

ImportWarnings::ImportWarnings() : heard_(std::make_shared<Heard>()) {
  // No default streams: nothing written to a file or the console.
  Assimp::DefaultLogger::create(nullptr, Assimp::Logger::NORMAL, 0);
  Assimp::DefaultLogger::get()->attachStream(new Listener(heard_), Assimp::Logger::Warn);
}

ImportWarnings::~ImportWarnings() { Assimp::DefaultLogger::kill(); }
#else
ImportWarnings::ImportWarnings() : heard_(std::make_shared<Heard>()) {}
ImportWarnings::~ImportWarnings() = default;
#endif

void ImportWarnings::refuse_dropped(const std::string& path, const std::string& importer_error) const {
  if (!heard_->first) return;
  const std::string also = importer_error.empty() ? "" : "; the importer: " + model_words::one_line(importer_error, 200);
  throw InputError(path + ": " + heard_->first->meaning + also);
}

}  // namespace opsila
