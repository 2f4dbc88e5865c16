// The importer's scene -> CONTRACT's scene. Kept apart from the importer's own
// post-processing: no aiProcess_Triangulate (CONTRACT fans polygons itself and
// keeps one facet id per face) and no aiProcess_PreTransformVertices (it
// joins and reorders meshes, and so would change the object ids).
#include "formats/assimp/model_import.h"

#include <fcntl.h>
#include <signal.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <new>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/env_hooks.h"
#include "core/host_memory.h"
#include "core/last_words.h"
#include "core/util.h"
#include "formats/assimp/import_warnings.h"
#include "formats/assimp/model_checks.h"
#include "formats/common/model_fan.h"
#include "formats/common/model_files.h"
#include "formats/common/model_words.h"
#include "formats/obj/obj_loader.h"
#include "formats/assimp/model_materials.h"
#include "formats/assimp/model_window.h"
#include "formats/ply/ply_reader.h"
#include "formats/stl/stl_format.h"

#ifdef OPSILA_HAVE_ASSIMP
#include <assimp/Importer.hpp>
#include <assimp/BaseImporter.h>
#include <assimp/importerdesc.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#endif

namespace opsila {

namespace fs = std::filesystem;

#ifdef OPSILA_HAVE_ASSIMP
namespace {

// The importer draws a skeleton that has no surfaces (BVH, CSM, an MD5
// animation alone) as stand-in shapes around its bones, in one material it
// names so and gives no colour: a black shape no file holds.
bool bones_only(const aiScene& ai) {
  aiString name;
  for (unsigned m = 0, k = 0; m < ai.mNumMeshes; ++m)
    if ((k = ai.mMeshes[m]->mMaterialIndex) >= ai.mNumMaterials ||
        ai.mMaterials[k]->Get(AI_MATKEY_NAME, name) != AI_SUCCESS || std::string(name.C_Str()) != "SkeletonMaterial")
      return false;
  return ai.mNumMeshes > 0;
}

// Every placement of every mesh: the product of the node transforms from the
// root down to each node that lists the mesh, in depth-first order. Without
// recursion; a hierarchy deeper than kMaxNodeDepth is refused (the glTF
// checks refuse one before the importer builds it). The importer may add
// one root above the file's own.
void collect_placements(const aiNode* root, unsigned num_meshes, std::vector<std::vector<aiMatrix4x4>>& out,
                        const std::string& name) {
  struct Pending {
    const aiNode* node;
    aiMatrix4x4 parent;
    int depth;
  };
  std::vector<Pending> stack{{root, aiMatrix4x4(), 0}};
  while (!stack.empty()) {
    const Pending at = stack.back();
    stack.pop_back();
    if (!at.node) continue;
    if (at.depth > kMaxNodeDepth + 1)
      throw InputError(name + ": node hierarchy more than " + std::to_string(kMaxNodeDepth) +
                       " levels deep (the limit)");
    const aiMatrix4x4 world = at.parent * at.node->mTransformation;
    for (unsigned k = 0; k < at.node->mNumMeshes; ++k)
      if (at.node->mMeshes[k] < num_meshes) out[at.node->mMeshes[k]].push_back(world);
    for (unsigned c = at.node->mNumChildren; c-- > 0;) stack.push_back({at.node->mChildren[c], world, at.depth + 1});
  }
}

class ModelReader {
 public:
  ModelReader(const aiScene& ai, const std::string& name, const std::string& base_dir, MapImages images,
              std::size_t max_triangles)
      : ai_(ai), name_(name), base_dir_(base_dir), images_(images), max_triangles_(max_triangles) {}

  Scene run() {
    if (bones_only(ai_))
      throw InputError(name_ + ": a skeleton (motion capture), no surfaces: nothing to draw; the importer's stand-in "
                               "shapes for its bones are not drawn");
    scene_.has_camera = false;
    scene_.has_lights = false;
    scene_.materials.push_back(MaterialDesc::default_material());
    material_index_ = import_materials(ai_, name_, base_dir_, scene_, images_);
    std::vector<std::vector<aiMatrix4x4>> placements(ai_.mNumMeshes);
    collect_placements(ai_.mRootNode, ai_.mNumMeshes, placements, name_);
    int unplaced = 0, facet = 0, skipped = 0;
    FanTally tally;
    for (unsigned m = 0; m < ai_.mNumMeshes; ++m) {
      const aiMesh* mesh = ai_.mMeshes[m];
      if (placements[m].empty()) ++unplaced;
      const int first_facet = facet;
      for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
        if (mesh->mFaces[f].mNumIndices >= 3) ++facet;
        else ++skipped;
        if (facet < 0) throw InputError(name_ + ": too many facets for 32-bit ids");
      }
      for (std::size_t k = 0; k < placements[m].size(); ++k)
        emit_mesh(*mesh, static_cast<int>(m), first_facet, placements[m][k], static_cast<int>(k), tally);
    }
    scene_.num_objects = std::max(1, static_cast<int>(ai_.mNumMeshes));
    scene_.num_facets = facet;
    for (std::string& w : fan_warnings(name_, skipped, unplaced, tally.degenerate)) scene_.warnings.push_back(std::move(w));
    if (scene_.triangles.empty()) throw InputError(name_ + ": no facets (the model has no drawable polygons)");
    check_scene_extent(scene_, name_);
    Vec3 lo, hi;
    scene_.bounds(lo, hi);
    scene_.camera = frame_bounds(lo, hi, 45.0f, float(scene_.width) / float(scene_.height));
    return std::move(scene_);
  }

 private:
  // One placement of a mesh (model_fan.h).
  void emit_mesh(const aiMesh& mesh, int object, int facet, const aiMatrix4x4& place, int placement,
                 FanTally& tally) {
    const int material = mesh.mMaterialIndex < material_index_.size() ? material_index_[mesh.mMaterialIndex] : 0;
    MeshFan fan(name_, mesh, place, max_triangles_, tally);
    fan.placement = placement;
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices < 3) continue;
      fan.face(face.mIndices, face.mNumIndices, f, object, facet++, material, &scene_);
    }
  }

  const aiScene& ai_;
  const std::string& name_;
  std::string base_dir_;
  MapImages images_;
  std::size_t max_triangles_;
  Scene scene_;
  std::vector<int> material_index_;  // importer material -> Scene::materials
};

// The importer's readers are not ours and some loop forever on malformed
// files (Debian's PLY reader on some headers). A read that outlives its
// budget ends the run with one error line instead of a hang; nothing has been
// written yet while a scene loads, so there is no output to clean up.
// Budget: OPSILA_IMPORT_TIMEOUT seconds if set, else 10 s + 1 s per MiB
// (a truncated SMD or OpenGEX file of a few bytes loops until it).
//
// Memory too: a corrupted Q3O file made the library's reader take 19 GB in
// its time. The resident memory the read adds is polled every 20 ms and
// bounded by import_memory_budget (model_checks.h).
std::uint64_t resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  unsigned long long size = 0, resident = 0;
  if (!(statm >> size >> resident)) return 0;
  return resident * static_cast<std::uint64_t>(sysconf(_SC_PAGESIZE));
}

// Where a failed import's one error line goes: the run's standard error,
// while the importer's own stderr is shut (ImportStderr).
int g_error_fd = 2;

// Seconds on the monotonic clock (async-signal-safe).
double monotonic_seconds() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// The importer prints to stderr on its way to a failure (a failed
// assertion's text, the runtime's "terminate called after ..."): one error
// line is the rule, so while it reads, its stderr goes to /dev/null and
// opsila's own line (watchdog, fault guard) to the saved descriptor.
class ImportStderr {
 public:
  ImportStderr() {
    saved_ = dup(2);
    const int null = open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved_ < 0 || null < 0 || dup2(null, 2) < 0) {
      if (null >= 0) close(null);
      if (saved_ >= 0) close(saved_);
      saved_ = -1;
      return;
    }
    close(null);
    g_error_fd = saved_;
  }
  ~ImportStderr() {
    if (saved_ < 0) return;
    g_error_fd = 2;
    dup2(saved_, 2);
    close(saved_);
  }
  ImportStderr(const ImportStderr&) = delete;
  ImportStderr& operator=(const ImportStderr&) = delete;

 private:
  int saved_ = -1;
};

class ImportWatchdog {
 public:
  ImportWatchdog(const std::string& name, std::uintmax_t bytes) {
    double budget = 10.0 + double(bytes) / (1024.0 * 1024.0);
    if (const char* env = env_hook(EnvHook::import_timeout)) {
      char* end = nullptr;
      const double v = std::strtod(env, &end);
      if (end == env || *end != '\0' || !(v >= 0 && v <= 1e9))
        throw InputError(std::string(env_hook_name(EnvHook::import_timeout)) + "=" + env +
                         ": expected a number of seconds, 0 to 1e9");
      budget = v;
    }
    const std::uint64_t memory = import_memory_budget(bytes);
    message_ = "opsila: error: " + last_words_prefix() + shown_text(name) + ": the model importer did not finish within " +
               std::to_string(static_cast<long long>(budget + 0.5)) + " s (malformed file?)\n";
    memory_message_ = "opsila: error: " + last_words_prefix() + shown_text(name) + ": the model importer took more than " +
                      std::to_string(memory >> 20) + " MiB of memory reading a file of " + std::to_string(bytes) +
                      " bytes (malformed file?)\n";
    const std::uint64_t base = resident_bytes();
    const double start = monotonic_seconds();
    thread_ = std::thread([this, budget, memory, base, start] {
      std::unique_lock<std::mutex> lock(mutex_);
      const auto deadline = std::chrono::steady_clock::now() +
                            std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                std::chrono::duration<double>(std::min(budget, 1e9)));
      for (;;) {
        const auto next = std::min<std::chrono::steady_clock::time_point>(
            deadline, std::chrono::steady_clock::now() + std::chrono::milliseconds(20));
        if (done_cv_.wait_until(lock, next, [this] { return done_; })) return;
        const bool late = std::chrono::steady_clock::now() >= deadline;
        const std::uint64_t now = resident_bytes();
        if (late || now > base + memory) {
          const std::string& text = late ? message_ : memory_message_;
          // 2: the exit code of bad input (app/args.h)
          say_last_words(g_error_fd, text.c_str(), text.size(), monotonic_seconds() - start, 2);
        }
      }
    });
  }
  ~ImportWatchdog() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    done_cv_.notify_one();
    thread_.join();
  }
  ImportWatchdog(const ImportWatchdog&) = delete;
  ImportWatchdog& operator=(const ImportWatchdog&) = delete;

 private:
  std::string message_, memory_message_;
  std::mutex mutex_;
  std::condition_variable done_cv_;
  bool done_ = false;
  std::thread thread_;
};

// Some of the importer's readers (Half-Life MDL, LightWave, ... : the
// formats opsila does not check first, so not fuzzed) fault or assert on
// truncated or corrupt files. While such a read runs on the import
// thread, a fault there (SIGSEGV, SIGBUS, SIGFPE, SIGILL) or an abort
// (a failed assertion, an exception no one catches) ends the run with one
// error line naming the file and exit code 2, like the watchdog: nothing
// has been written yet while a scene loads. The handler runs on its own
// stack (the fault may be a stack overflow) and calls only write and
// _exit. Models read from memory (the fuzzers) get no guard, so that a
// fault there is still found.
class ImportFaultGuard {
 public:
  explicit ImportFaultGuard(const std::string& name) {
    std::snprintf(message_, sizeof message_,
                  "opsila: error: %s%s: the model importer failed while reading it (malformed file?)\n",
                  last_words_prefix().c_str(), name.size() < 3000 ? shown_text(name).c_str() : "the model");
    length_ = std::strlen(message_);
    start_ = monotonic_seconds();
    alt_.resize(std::max<std::size_t>(SIGSTKSZ, 64 * 1024));
    stack_t st{};
    st.ss_sp = alt_.data();
    st.ss_size = alt_.size();
    sigaltstack(&st, &old_stack_);
    struct sigaction sa {};
    sa.sa_handler = &ImportFaultGuard::on_fault;
    sa.sa_flags = SA_ONSTACK;
    sigemptyset(&sa.sa_mask);
    for (int k = 0; k < kSignals; ++k) sigaction(kSignal[k], &sa, &old_[k]);
    old_terminate_ = std::set_terminate([] { on_fault(SIGABRT); });  // an exception no one catches
  }
  ~ImportFaultGuard() {
    std::set_terminate(old_terminate_);
    for (int k = 0; k < kSignals; ++k) sigaction(kSignal[k], &old_[k], nullptr);
    sigaltstack(&old_stack_, nullptr);
  }
  ImportFaultGuard(const ImportFaultGuard&) = delete;
  ImportFaultGuard& operator=(const ImportFaultGuard&) = delete;

 private:
  static void on_fault(int) {
    say_last_words(g_error_fd, message_, length_, monotonic_seconds() - start_, 2);  // 2: bad input (app/args.h)
  }
  static constexpr int kSignals = 5;
  static constexpr int kSignal[kSignals] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
  static inline char message_[4096];
  static inline std::size_t length_ = 0;
  static inline double start_ = 0;
  std::vector<char> alt_;
  stack_t old_stack_{};
  struct sigaction old_[kSignals] {};
  std::terminate_handler old_terminate_ = nullptr;
};

// The extension without its dot, in lower case.
std::string bare_extension(const std::string& ext) {
  std::string e = lower(ext);
  if (!e.empty() && e[0] == '.') e.erase(0, 1);
  return e;
}

// Only the readers that claim the file's extension may read it. Where
// several claim it (.gltf and .glb in libassimp 5.2) the importer would
// otherwise try, when those refuse the content, every reader whose keyword
// appears in the first bytes, and some of them allocate whatever a header
// asks before reading anything (fuzz_model: OFF text and a Quick3D header,
// both named .gltf, asked for 45 GB and 1.2 TB). The others are unregistered
// (and deleted: the importer no longer owns them). Not for .xml: several
// XML formats (Ogre's .mesh.xml, XGL, ...) are told apart only by content.
void keep_readers_for(Assimp::Importer& importer, const std::string& ext) {
  const std::string e = bare_extension(ext);
  if (e == "xml") return;
  std::vector<Assimp::BaseImporter*> others;
  for (std::size_t i = 0; i < importer.GetImporterCount(); ++i) {
    std::istringstream list(importer.GetImporterInfo(i)->mFileExtensions);
    std::string one;
    bool claims = false;
    while (list >> one) claims = claims || lower(one) == e;
    if (!claims) others.push_back(importer.GetImporter(i));
  }
  for (Assimp::BaseImporter* reader : others)
    if (importer.UnregisterLoader(reader) == aiReturn_SUCCESS) delete reader;
}

// aiProcess_ValidateDataStructure refuses inconsistent data (indices out of
// range, ...) instead of handing it on.
constexpr unsigned kImportFlags = aiProcess_ValidateDataStructure;

// STL is read without that step; its scene is checked instead
// (stl::check_imported_scene says why).
bool validated_by_us(const std::string& ext) { return lower(ext) == ".stl"; }

Scene convert(Assimp::Importer& importer, const aiScene* ai, const std::string& name, const std::string& base_dir,
              const ModelFiles& files, MapImages images, std::size_t max_triangles) {
  if (!ai) {
    const std::string said = model_words::one_line(importer.GetErrorString(), 200);
    std::string why = "the model importer cannot read it" + (said.empty() ? "" : ": " + said);
    // The importer catches its own allocation failure and says only this.
    if (said.find("bad_alloc") != std::string::npos)
      why = "the model importer ran out of memory reading it (a count in the file asks for more than this process may "
            "use)";
    throw InputError(name + ": " + why + (files.refusal().empty() ? "" : " (" + files.refusal() + ")"));
  }
  if (!ai->mRootNode || ai->mNumMeshes == 0)
    throw InputError(name + ": no facets (the model has no meshes)");
  // No mesh read (cameras or lights only, a motion capture): the importer
  // marks the scene incomplete and adds stand-in shapes, one a node.
  const std::string only = std::to_string(ai->mNumCameras) + " camera(s) and " + std::to_string(ai->mNumLights);
  if (ai->mFlags & AI_SCENE_FLAGS_INCOMPLETE)
    throw InputError(name + ": no facets: the model importer found no surfaces in it (" +
                     (ai->mNumCameras + ai->mNumLights > 0 ? only + " light(s) only" : "nodes or bones only") +
                     "); its stand-in shapes for the nodes are not drawn");
  try {
    return ModelReader(*ai, name, base_dir, images, max_triangles).run();
  } catch (const std::bad_alloc&) {
    throw InputError(name + ": out of memory while loading (model too large)");
  } catch (const std::length_error&) {
    throw InputError(name + ": model too large to load");
  }
}

// A PLY or STL file the importer refuses and the project's own stream reads
// (model_window.h): the stream's counting read names the line and key of
// the first problem, as a rank reading its share would; else the importer's
// text stays. Only on the way to an error: no file is read twice.
void explain_with_stream(const std::string& path) {
  if (!is_streamed_model(path) || !model_stream_refusal(path).empty()) return;
  std::uint64_t fans = 0;
  (void)load_model_window(path, std::size_t(1) << 40, ModelWindow{}, fans);
}

// The stack of the import thread: the importer's readers, its validation
// and its scene's destructor recurse once per node level (kMaxNodeDepth at
// most from glTF; other formats are not checked before the importer builds
// them) and once per level of JSON or XML nesting. Reserved, not touched,
// until used.
constexpr std::size_t kImportStackBytes = std::size_t(256) << 20;

// The file's shape checks, then the importer, through `files` (which
// records every file read as an input of the scene), on a thread with a
// large stack.
Scene import_model(ModelFiles& files, const std::string& path, const std::string& base_dir, bool watched,
                   MapImages images, std::size_t max_triangles = kMaxTriangles) {
  Scene scene;
  run_with_stack(kImportStackBytes, [&] {
    const std::string ext = fs::path(path).extension().string();
    const std::uint64_t input_bytes = check_model_file_shape(files, path, ext);
    Assimp::Importer importer;
    importer.SetIOHandler(files.io_system());  // the importer owns it
    keep_readers_for(importer, ext);
    const aiScene* ai = nullptr;
    const ImportWarnings warnings;  // before the importer: it may drop faces and go on
    const bool our_checks = validated_by_us(ext);
    const unsigned flags = our_checks ? 0u : kImportFlags;
    if (watched) {
      const ImportStderr quiet;
      const ImportWatchdog watchdog(path, input_bytes);
      const ImportFaultGuard guard(path);
      ai = importer.ReadFile(path, flags);
    } else {
      ai = importer.ReadFile(path, flags);
    }
    if (!ai && !base_dir.empty()) explain_with_stream(path);  // a file on disk (not a model in memory)
    warnings.refuse_dropped(path, ai ? "" : importer.GetErrorString());
    if (ai && our_checks) stl::check_imported_scene(*ai, path);
    scene = convert(importer, ai, path, base_dir, files, images, max_triangles);
  });
  scene.input_files.insert(scene.input_files.begin(), files.files().begin(), files.files().end());
  return scene;
}

}  // namespace

bool is_imported_model(const std::string& path) {
  const std::string ext = lower(fs::path(path).extension().string());
  if (ext.size() < 2 || ext == ".obj" || ext == ".json") return false;
  Assimp::Importer importer;
  return importer.IsExtensionSupported(ext.c_str());
}

Scene load_model(const std::string& path, MapImages images, std::size_t max_triangles) {
  ModelFiles files;
  files.size(path);  // the usual messages for a missing, special or huge file
  const bool ply = lower(fs::path(path).extension().string()) == ".ply";
  if (ply && ply_has_strips(path)) return load_ply_whole(path, max_triangles);  // the importer keeps one triangle
  std::string dir = fs::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  Scene scene = import_model(files, path, dir, true, images, max_triangles);
  if (ply)
    for (std::string& w : ply_unread_elements(path)) scene.warnings.push_back(std::move(w));
  return scene;
}

Scene load_model_from_memory(const std::string& bytes, const std::string& name, const std::string& hint,
                             const std::string& other) {
  // The importer picks its reader by the name's extension.
  const std::string path = bare_extension(fs::path(name).extension().string()) == lower(hint) ? name : name + "." + hint;
  if (lower(hint) == "ply" && ply_has_strips(path, &bytes)) return load_ply_whole(path, kMaxTriangles, &bytes);
  ModelFiles files(path, bytes, other);
  return import_model(files, path, "", false, MapImages::now);
}

#else  // built without the Open Asset Import Library

bool is_imported_model(const std::string& path) {
  static const char* const kCommon[] = {".ply", ".stl", ".gltf", ".glb", ".fbx", ".dae", ".3ds", ".off", ".blend"};
  const std::string ext = lower(fs::path(path).extension().string());
  for (const char* e : kCommon)
    if (ext == e) return true;
  return false;
}

Scene load_model(const std::string& path, MapImages, std::size_t) {
  ModelFiles().size(path);  // the usual messages for a missing, special or huge file
  throw InputError(path + ": this build has no Open Asset Import Library (install libassimp-dev and rebuild)");
}

Scene load_model_from_memory(const std::string&, const std::string& name, const std::string&, const std::string&) {
  throw InputError(name + ": this build has no Open Asset Import Library");
}

#endif

}  // namespace opsila
