#include "formats/assimp/import_warnings.h"

#include <cstring>

#include "core/errors.h"
#include "core/util.h"
#include "formats/common/model_words.h"

#ifdef OPSILA_HAVE_ASSIMP
#include <assimp/DefaultLogger.hpp>
#include <assimp/LogStream.hpp>
#endif

namespace opsila {

namespace {

// The importer's words (Debian's assimp 5.2) and what they mean here;
// with `quoted`, heard only as an error (its warnings with those words
// come with sound files too), and its message, which names the object's
// byte, is added.
struct Dropped {
  const char* said;
  const char* meaning;
  bool quoted = false;
};
constexpr Dropped kDropped[] = {
    {"out-of-range indices", "a mesh primitive's indices name vertices past the end of its attributes (the importer "
                             "would drop those faces): every index must be below the POSITION accessor's count"},
    {"not compatible with the TRIANGLES mode", "a triangles primitive's vertex or index count is not a multiple of 3 "
                                               "(the importer would drop the rest)"},
    {"3DS: Vertex index overflow", "a 3DS face names a vertex past its mesh's vertex list (the importer would put "
                                   "the mesh's last vertex in its place)"},
    // A binary FBX object it cannot read (an index past the vertices, an
    // array that does not inflate) is left out with the mesh that uses it.
    {"FBX-DOM", "an FBX object the importer cannot read (it would leave it and the mesh that uses it out)", true},
    {"FBX-Parser", "an FBX object the importer cannot read (it would leave it and the mesh that uses it out)", true},
    {"CompressionFailure", "an FBX array that does not inflate (compressed data damaged: the importer would leave "
                           "its object out)"},
};

}  // namespace

struct ImportWarnings::Heard {
  const Dropped* first = nullptr;
  std::string said;  // the importer's message, where the meaning quotes it
};

#ifdef OPSILA_HAVE_ASSIMP
namespace {

// Owned by the logger once attached; writes into the Heard it shares.
class Listener : public Assimp::LogStream {
 public:
  explicit Listener(std::shared_ptr<ImportWarnings::Heard> heard) : heard_(std::move(heard)) {}
  void write(const char* message) override {
    if (heard_->first) return;
    const bool error = std::strncmp(message, "Error", 5) == 0;
    const char* text = std::strstr(message, ": ");  // after "Error, T0"
    for (const Dropped& d : kDropped)
      if (!heard_->first && (!d.quoted || error) && std::strstr(message, d.said)) {
        heard_->first = &d;
        if (d.quoted) heard_->said = model_words::one_line(trim_blanks(text ? text + 2 : message), 200);
      }
  }

 private:
  std::shared_ptr<ImportWarnings::Heard> heard_;
};

}  // namespace

ImportWarnings::ImportWarnings() : heard_(std::make_shared<Heard>()) {
  // No default streams: nothing written to a file or the console.
  Assimp::DefaultLogger::create(nullptr, Assimp::Logger::NORMAL, 0);
  Assimp::DefaultLogger::get()->attachStream(new Listener(heard_), Assimp::Logger::Warn | Assimp::Logger::Err);
}

ImportWarnings::~ImportWarnings() { Assimp::DefaultLogger::kill(); }
#else
ImportWarnings::ImportWarnings() : heard_(std::make_shared<Heard>()) {}
ImportWarnings::~ImportWarnings() = default;
#endif

void ImportWarnings::refuse_dropped(const std::string& path, const std::string& importer_error) const {
  if (!heard_->first) return;
  const std::string also = importer_error.empty() ? "" : "; the importer: " + model_words::one_line(importer_error, 200);
  const std::string said = heard_->said.empty() ? "" : " (the importer: " + heard_->said + ")";
  throw InputError(path + ": " + heard_->first->meaning + said + also);
}

}  // namespace opsila
