// The output files of one run, all or nothing: each is written complete to a
// temporary file next to its destination, and only when every one of them is
// written are they all renamed into place. A failure (a full disk), an error
// or SIGINT/SIGTERM leaves no output and no temporary file behind. No output
// may name an input of the run or another output.
#pragma once

#include <string>
#include <vector>

namespace opsila {

// Installs SIGINT and SIGTERM handlers that remove the temporary files of
// every OutputFiles not yet committed and exit with 128 + the signal number
// (130, 143). Only async-signal-safe calls (unlink, _exit) run in them.
void install_interrupt_cleanup();

// True when a and b name the same file: the same inode if both exist, else
// the same path once made absolute and normalised (links resolved).
bool same_file(const std::string& a, const std::string& b);

class OutputFiles {
 public:
  OutputFiles() = default;
  OutputFiles(const OutputFiles&) = delete;
  OutputFiles& operator=(const OutputFiles&) = delete;
  ~OutputFiles();  // removes what was not committed

  // Declares an output (`flag` names it in messages). Throws InputError if
  // it could not be created (check_output_path), or names an output already
  // declared. Nothing is created.
  void declare(const std::string& flag, const std::string& path);
  // A folder that holds outputs (bench --csv): checked now, created only by
  // write(), and removed again if the run fails after creating it. The
  // `names` it will hold are checked now too: no folder in their place, and
  // (refuse_inputs) no input.
  void declare_folder(const std::string& flag, const std::string& folder, const std::vector<std::string>& names = {});
  // Throws InputError if a declared output is one of `inputs` (the scene,
  // its models, material libraries, textures); outputs written later into a
  // declared folder are checked against them too.
  void refuse_inputs(const std::vector<std::string>& inputs);

  // Writes a declared output's bytes (or a new file in the declared folder)
  // to its temporary file. Throws
  // InputError("PATH: cannot write (reason)") after removing every
  // temporary file of this set.
  void write(const std::string& path, const std::string& bytes);
  // Renames every written output into place. SIGINT/SIGTERM are held back
  // meanwhile, so the set appears whole or (on a failed rename) not at all.
  void commit();

 private:
  struct Entry {
    std::string flag, path, temp;
    int slot = -1;  // in the signal handler's table while temp exists
    bool in_folder = false;
    std::string dest;  // where it lands: `path`, or the file a link there names (output_destination)
  };
  void discard() noexcept;
  [[noreturn]] void fail_commit(const std::vector<std::string>& kept, const std::vector<std::size_t>& order,
                                std::size_t done, const std::string& path, const std::string& reason);
  Entry& entry_for(const std::string& path);

  std::vector<Entry> entries_;
  std::vector<std::string> inputs_;
  std::string folder_flag_, folder_;
  std::vector<std::string> folder_names_;
  bool folder_created_ = false;
};

}  // namespace opsila
