// The importer's warnings (and errors) that mean it dropped part of the file
// and went on: a glTF primitive whose indices name vertices past its
// attributes loses those faces, a triangles primitive whose vertex count is
// no multiple of 3 loses the rest, a 3DS face past its vertices takes the
// last one, a binary FBX object it cannot read is left out with its mesh,
// and the render would show other than the file holds, with exit 0. Heard while one import runs (the importer speaks through a
// logger of its own, process-wide: imports run one at a time), and turned
// into one InputError naming the file.
#pragma once

#include <memory>
#include <string>

namespace opsila {

class ImportWarnings {
 public:
  ImportWarnings();  // attaches a listener to the importer's logger
  ~ImportWarnings();  // and takes it away
  ImportWarnings(const ImportWarnings&) = delete;
  ImportWarnings& operator=(const ImportWarnings&) = delete;

  // Throws InputError("PATH: ...") when the importer said it dropped part
  // of the file; `importer_error`, its own refusal where it gave up, is
  // added (an all-out-of-range mesh ends in "has no faces").
  void refuse_dropped(const std::string& path, const std::string& importer_error) const;

  struct Heard;  // what the listener heard (import_warnings.cpp)

 private:
  std::shared_ptr<Heard> heard_;
};

}  // namespace opsila
