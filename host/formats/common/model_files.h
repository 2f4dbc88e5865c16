// Every file a model import reads, seen before it is read: the model itself
// and whatever the importer opens by itself (a glTF's .bin buffers and
// images, an MTL next to a format that names one, ...). Each is recorded as
// an input of the run (no output may name it), must be a regular file within
// kMaxInputFileBytes, and is only ever opened for reading. The same files can
// come from memory instead (fuzz_model), so that crafted external buffers
// take the same path as files on disk.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace Assimp {
class IOSystem;
}

namespace opsila {

class ModelFiles {
 public:
  // Files on disk.
  ModelFiles() = default;
  // Files in memory: `main_name` holds `main`; any other name the importer
  // asks for holds `other` (absent when it is empty). Nothing is read from disk.
  ModelFiles(std::string main_name, std::string main, std::string other);

  // Size of a file after the checks (regular, within the limit); records it.
  // Throws InputError("PATH: ...") when it cannot be read.
  std::uint64_t size(const std::string& path);
  // Whether something is at `path` (no checks, nothing recorded).
  bool exists(const std::string& path) const;
  // Up to `max_bytes` from the start of a file (the same checks).
  std::string head(const std::string& path, std::size_t max_bytes);

  // The importer reads `bytes` where it opens `path`, which the checks have
  // read as it is (a glTF without what opsila does not use, gltf_still.h).
  void substitute(const std::string& path, std::string bytes);

  // An IOSystem for Assimp::Importer::SetIOHandler (which takes ownership)
  // that opens files through this object; it must not outlive it.
  Assimp::IOSystem* io_system();

  // Every file seen, in the order first seen.
  const std::vector<std::string>& files() const { return files_; }
  // Why the last refused file was refused ("" when none was): the importer's
  // own message for a file it could not open names neither file nor reason.
  const std::string& refusal() const { return refusal_; }

 private:
  friend class ModelIOSystem;
  void record(const std::string& path);
  const std::string* in_memory(const std::string& path) const;

  bool memory_ = false;
  std::string main_name_, main_, other_;
  std::string substitute_name_, substitute_;
  std::vector<std::string> files_;
  std::string refusal_;
};

// Runs `work` on a thread with a stack of `stack_bytes` and waits for it;
// an exception it throws is rethrown here. The importer's readers and its
// scene's destructor recurse once per level of nesting.
void run_with_stack(std::size_t stack_bytes, const std::function<void()>& work);

}  // namespace opsila
