// Outputs are all or nothing and never land on an input: a failed write, an
// output naming an input or another output, an interrupted render.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <cstdlib>
#include <thread>

#include "formats/image/image_io.h"
#include "formats/image/output_files.h"
#include "scene/scene.h"
#include "test_util.h"

namespace opsila {
namespace {

using test::RunResult;
using test::TempDir;
using test::run_opsila;

const char* kScene = R"({"image": {"width": 64, "height": 48}, "lights": [{"position": [0, 5, 5]}],
  "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}]})";

using Names = std::vector<std::string>;

TEST(Outputs, NoOutputMayNameTheSceneOrAFileItReads) {
  TempDir dir;
  const std::string mtl = dir.write("lib.json", "newmtl red\nKd 1 0 0\nmap_Kd tex.png\n");
  const std::string obj = dir.write(
      "model.json", "mtllib lib.json\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl red\n"
                    "f 1/1 2/2 3/3\n");
  const std::string texture = dir.file("tex.png");
  write_png(texture, 2, 2, std::vector<float>(12, 0.5f));
  const std::string scene = dir.write(
      "scene.json", R"({"objects": [{"type": "obj", "file": "model.json"}], "image": {"size": [8, 8]}})");
  ASSERT_EQ(::symlink("scene.json", dir.file("link.json").c_str()), 0);
  const Names before = dir.entries();
  for (const std::string& victim : {scene, obj, mtl, dir.file("link.json"), dir.path() + "/./scene.json"}) {
    SCOPED_TRACE(victim);
    const RunResult r =
        run_opsila({"render", scene, "-o", dir.file("x.png"), "--stats", victim, "--reference"});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("--stats " + victim + ": is an input of this run"), std::string::npos) << r.err;
    EXPECT_EQ(r.error_lines().size(), 1u);
    EXPECT_EQ(dir.entries(), before);
  }
  const RunResult tex = run_opsila({"render", scene, "-o", texture, "--reference"});
  EXPECT_EQ(tex.exit_code, 2) << tex.err;
  EXPECT_NE(tex.err.find("-o " + texture + ": is an input of this run"), std::string::npos) << tex.err;
  EXPECT_EQ(dir.entries(), before);
  EXPECT_EQ(test::read_file(scene).front(), '{');
  EXPECT_EQ(test::read_file(obj).rfind("mtllib", 0), 0u);
  EXPECT_EQ(test::read_file(mtl).rfind("newmtl", 0), 0u);
  // The bench's outputs too.
  const RunResult r = run_opsila({"bench", scene, "--json", dir.file("link.json"), "--quick"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("is an input of this run"), std::string::npos) << r.err;
  EXPECT_EQ(dir.entries(), before);
}

// The kernels a run builds from OPSILA_KERNEL_SOURCE are an input too:
// `--stats` of the same name replaced them.
TEST(Outputs, NoOutputMayNameTheKernelSource) {
  TempDir dir;
  const std::string scene = dir.write("s.json", kScene), kernels = dir.write("k.json", "kernels");
  for (const char* command : {"render", "bench"}) {
    std::vector<std::string> args = {command, scene, std::string(command) == "render" ? "--stats" : "--json", kernels};
    if (std::string(command) == "render") args.insert(args.end(), {"-o", dir.file("x.png")});
    const RunResult r = test::run_program(OPSILA_BINARY, args, {{"OPSILA_KERNEL_SOURCE", kernels}});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find(kernels + ": is an input of this run"), std::string::npos) << r.err;
    EXPECT_EQ(test::read_file(kernels), "kernels");
    EXPECT_EQ(dir.entries(), (Names{"k.json", "s.json"}));
  }
}

TEST(Outputs, NoOutputMayNameAnotherOutput) {
  TempDir dir;
  const std::string scene = dir.write("s.json", kScene);
  const std::string image = dir.write("x.png", "old");
  ASSERT_EQ(::symlink("x.png", dir.file("alias.npy").c_str()), 0);
  const RunResult r = run_opsila(
      {"render", scene, "-o", image, "--item-buffer", dir.file("alias.npy"), "--reference"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--item-buffer " + dir.file("alias.npy") + ": same file as -o"), std::string::npos)
      << r.err;
  EXPECT_EQ(test::read_file(image), "old");
}

// An output named by a symbolic link is written through it, as a shell's
// redirection or cp writes: the file it names is replaced, the link stays.
TEST(Outputs, AnOutputThatIsALinkIsWrittenThroughIt) {
  TempDir dir;
  const std::string scene = dir.write("s.json", kScene);
  ASSERT_EQ(::mkdir(dir.file("renders").c_str(), 0777), 0);
  dir.write("renders/x.png", "old");
  ASSERT_EQ(::symlink("renders/x.png", dir.file("link.png").c_str()), 0);  // relative to the link's folder
  ASSERT_EQ(::symlink(dir.file("renders/new.npy").c_str(), dir.file("items.npy").c_str()), 0);  // not there yet
  const RunResult r =
      run_opsila({"render", scene, "-o", dir.file("link.png"), "--item-buffer", dir.file("items.npy"), "--reference"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* link : {"link.png", "items.npy"}) {
    struct stat st;
    ASSERT_EQ(::lstat(dir.file(link).c_str(), &st), 0) << link;
    EXPECT_TRUE(S_ISLNK(st.st_mode)) << link;
  }
  EXPECT_EQ(test::read_file(dir.file("renders/x.png")).substr(1, 3), "PNG");
  EXPECT_EQ(test::read_file(dir.file("renders/new.npy")).substr(1, 5), "NUMPY");
  // A loop of links: one error naming the file, nothing written.
  ASSERT_EQ(::symlink("b.png", dir.file("a.png").c_str()), 0);
  ASSERT_EQ(::symlink("a.png", dir.file("b.png").c_str()), 0);
  const RunResult loop =
      run_opsila({"render", scene, "-o", dir.file("a.png"), "--item-buffer", dir.file("i.npy"), "--reference"});
  EXPECT_EQ(loop.exit_code, 2) << loop.err;
  ASSERT_EQ(loop.error_lines().size(), 1u) << loop.err;
  EXPECT_NE(loop.error_lines()[0].find(dir.file("a.png")), std::string::npos) << loop.err;
  EXPECT_FALSE(test::file_exists(dir.file("i.npy")));
}

// Names as long as a folder allows (255 bytes) are written: their
// temporary files, beside them, take a shorter name.
TEST(Outputs, TheLongestFileNamesAreWritten) {
  TempDir dir;
  const std::string scene = dir.write("s.json", kScene);
  const std::string image = dir.file(std::string(251, 'i') + ".png"), stats = dir.file(std::string(250, 's') + ".json");
  const RunResult r = run_opsila({"render", scene, "-o", image, "--stats", stats, "--reference", "-q"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::file_exists(image));
  EXPECT_TRUE(test::file_exists(stats));
  EXPECT_EQ(TempDir::list(dir.path()).size(), 3u) << "a temporary file was left behind";
}

// An append-only folder (chattr +a) takes new files but renames and removes
// none: the render wrote its temporary file there and could not take it
// back. Now the folder is refused before anything is written.
TEST(Outputs, AnAppendOnlyFolderIsRefusedBeforeAnythingIsWritten) {
  TempDir dir;
  const std::string scene = dir.write("s.json", kScene);
  // In the temporary folder, or where the build is (tmpfs keeps no such flag).
  std::string out;
  for (const std::string& at : {dir.file("out"), std::string(OPSILA_BINARY) + "-append-only-" + std::to_string(::getpid())}) {
    ::mkdir(at.c_str(), 0755);
    if (test::run_program("/usr/bin/chattr", {"+a", at}).exit_code == 0) {
      out = at;
      break;
    }
    ::rmdir(at.c_str());
  }
  if (out.empty()) GTEST_SKIP() << "chattr +a is refused here (it needs root and a file system that keeps the flag)";
  const RunResult r = run_opsila({"render", scene, "-o", out + "/o.png", "--reference", "-q"});
  const RunResult tables = run_opsila({"bench", scene, "--csv", out, "--quick", "-q"});
  test::run_program("/usr/bin/chattr", {"-a", out});  // so that the folder can be removed
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.err.find("o.png: cannot write (folder " + out + " is append-only"), std::string::npos) << r.err;
  EXPECT_EQ(tables.exit_code, 2) << tables.err;
  EXPECT_NE(tables.err.find("--csv " + out + ": the folder is append-only"), std::string::npos) << tables.err;
  EXPECT_TRUE(TempDir::list(out).empty()) << "a file was left in the folder";
  std::filesystem::remove_all(out);
}

// A file size limit makes the second output's write fail (EFBIG) as a full
// disk would, while the first (a small PNG) fits.
TEST(Outputs, AFailedWriteLeavesNoOutputAtAll) {
  TempDir dir;
  const std::string scene = dir.write("s.json", kScene);
  const std::string old_stats = dir.write("o.json", "old stats");
  const Names before = dir.entries();
  struct rlimit saved;
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
  struct rlimit small = saved;
  small.rlim_cur = 20000;  // PNG of 64x48 < 20000 bytes < item buffer (24704 bytes)
  void (*old_handler)(int) = ::signal(SIGXFSZ, SIG_IGN);
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  const RunResult r = run_opsila({"render", scene, "-o", dir.file("o.png"), "--item-buffer",
                                  dir.file("o.npy"), "--stats", old_stats, "--reference"});
  ::setrlimit(RLIMIT_FSIZE, &saved);
  ::signal(SIGXFSZ, old_handler);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("o.npy: cannot write"), std::string::npos) << r.err;
  EXPECT_EQ(r.error_lines().size(), 1u);
  EXPECT_EQ(dir.entries(), before);  // no image, no temporary file
  EXPECT_EQ(test::read_file(old_stats), "old stats");
  // Without the limit, all three appear.
  const RunResult ok = run_opsila({"render", scene, "-o", dir.file("o.png"), "--item-buffer",
                                   dir.file("o.npy"), "--stats", old_stats, "--reference"});
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_EQ(dir.entries(), (Names{"o.json", "o.npy", "o.png", "s.json"}));
}

// A rename that fails once others have succeeded (a table's name held by a
// A folder's tables are checked when it is declared (the bench's --csv):
// an input or a folder where one goes had been found after the whole run.
TEST(Outputs, AFoldersTablesAreCheckedBeforeTheRun) {
  TempDir dir;
  ASSERT_EQ(::mkdir(dir.file("tables").c_str(), 0755), 0);
  const std::string scene = dir.write("tables/phases.csv", "{}");
  ASSERT_EQ(::mkdir(dir.file("tables/levels.csv").c_str(), 0755), 0);
  {
    OutputFiles out;
    test::expect_error([&] { out.declare_folder("--csv", dir.file("tables"), {"levels.csv"}); },
                       {"--csv " + dir.file("tables/levels.csv") + ": a folder stands where the table goes"});
  }
  OutputFiles out;
  out.declare_folder("--csv", dir.file("tables"), {"phases.csv"});
  test::expect_error([&] { out.refuse_inputs({scene}); },
                     {"--csv " + dir.file("tables/phases.csv") + ": is an input of this run"});
  EXPECT_EQ(test::read_file(scene), "{}");
}

// folder; a busy mount point) put the new files in place of the old, then
// removed them: the user's earlier files of those names were lost. The old
// files now stay as they were.
TEST(Outputs, AFailedRenameLeavesTheOldFilesInPlace) {
  TempDir dir;
  const std::string old_a = dir.write("a.json", "old a");
  ASSERT_EQ(::mkdir(dir.file("tables").c_str(), 0755), 0);
  dir.write("tables/keep.csv", "old table");
  ASSERT_EQ(::mkdir(dir.file("tables/t.csv").c_str(), 0755), 0);  // a folder where a table goes
  {
    OutputFiles out;
    out.declare("--json", old_a);
    out.declare_folder("--csv", dir.file("tables"));
    out.write(old_a, "new a");
    out.write(dir.file("tables/keep.csv"), "new table");
    out.write(dir.file("tables/t.csv"), "t");
    test::expect_error([&] { out.commit(); }, {"t.csv: cannot write (Is a directory)"});
  }
  EXPECT_EQ(test::read_file(old_a), "old a");
  EXPECT_EQ(test::read_file(dir.file("tables/keep.csv")), "old table");
  EXPECT_EQ(dir.entries(), (Names{"a.json", "tables"}));
  // A rename refused by the system itself, after another's succeeded.
  const std::string busy = dir.write("busy.json", "old busy"), other = dir.write("other.json", "mounted");
  if (::geteuid() != 0 || std::system(("mount --bind " + other + " " + busy + " 2>/dev/null").c_str()) != 0)
    GTEST_SKIP() << "a bind mount (root, and a system that allows it) makes a rename fail with EBUSY";
  {
    OutputFiles out;
    out.declare("--json", old_a);
    out.declare("--stats", busy);
    out.write(old_a, "new a");
    out.write(busy, "new busy");
    test::expect_error([&] { out.commit(); }, {"busy.json: cannot write"});
  }
  EXPECT_EQ(std::system(("umount " + busy).c_str()), 0);
  EXPECT_EQ(test::read_file(old_a), "old a");
  EXPECT_EQ(test::read_file(busy), "old busy");
  EXPECT_EQ(dir.entries(), (Names{"a.json", "busy.json", "other.json", "tables"}));
}

// The file-size limit with SIGXFSZ left at its default (a user's `ulimit
// -f`, set by a shell in the child only): a write error like any other, not
// a process killed by the signal with its temporary file left behind.
TEST(Outputs, TheFileSizeLimitIsAWriteError) {
  TempDir dir;
  const std::string scene = dir.write("s.json", kScene);
  const Names before = dir.entries();
  std::vector<std::string> outputs = {"o.pfm"};  // (a 64x48 PNG of this scene may fit)
  if (exr_available()) outputs.push_back("o.exr");
  for (const std::string& name : outputs) {
    SCOPED_TRACE(name);
    // 4 blocks (2 or 4 KiB, as the shell counts them): under every 64x48 image.
    const RunResult r = test::run_program(
        "/bin/sh", {"-c", "ulimit -f 4 && exec \"$0\" \"$@\"", OPSILA_BINARY, "render", scene, "-o",
                    dir.file(name), "--reference", "-q"});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.err.find(name + ": cannot write (File too large)"), std::string::npos) << r.err;
    EXPECT_EQ(dir.entries(), before);  // no image, no temporary file
  }
}

TEST(Outputs, BenchCreatesNothingBeforeItsInputIsRead) {
  TempDir dir;
  const RunResult r = run_opsila({"bench", dir.file("MISSING.json"), "--csv", dir.file("tables"),
                                  "--json", dir.file("b.json"), "--quick"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_TRUE(dir.entries().empty()) << dir.entries().front();
}

// In a child process: two outputs, the first written, then a signal (a
// closed terminal's SIGHUP, or a timer's, left a temporary file before).
TEST(Outputs, ASignalRemovesTemporaryFilesAndExitsWith128PlusIt) {
  for (const int sig : {SIGINT, SIGTERM, SIGHUP, SIGALRM, SIGQUIT}) {
    TempDir dir;
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      install_interrupt_cleanup();
      OutputFiles outputs;
      outputs.declare("-o", dir.file("a.pfm"));
      outputs.declare("--stats", dir.file("b.json"));
      outputs.write(dir.file("a.pfm"), "bytes");
      if (TempDir::list(dir.path()).size() != 1) ::_exit(1);  // the temporary file is there
      ::raise(sig);
      ::_exit(2);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 128 + sig);
    EXPECT_TRUE(dir.entries().empty()) << dir.entries().front();
  }
}

// A signal the caller ignores (nohup's SIGHUP) stays ignored: the run goes on.
TEST(Outputs, AnIgnoredHangUpStaysIgnored) {
  TempDir dir;
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::signal(SIGHUP, SIG_IGN);
    install_interrupt_cleanup();
    OutputFiles outputs;
    outputs.declare("-o", dir.file("a.pfm"));
    outputs.write(dir.file("a.pfm"), "bytes");
    ::raise(SIGHUP);
    outputs.commit();
    ::_exit(7);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 7);
  EXPECT_EQ(dir.entries(), (Names{"a.pfm"}));
}

// An endless render (two facing mirrors, depth 31: 2^31 rays a pixel is
// beyond patience).
const char* kSlabs = R"({"image": {"size": [64, 48]}, "depth": 31,
    "camera": {"eye": [0, 0, 0.5], "look_at": [0, 0, -1]},
    "materials": {"glass": {"kr": 0.9, "kt": 0.9, "Ni": 1.5}},
    "objects": [{"type": "box", "min": [-50, -50, -1.1], "max": [50, 50, -1], "material": "glass"},
                {"type": "box", "min": [-50, -50, 1], "max": [50, 50, 1.1], "material": "glass"}]})";

// A shell's plain `ulimit -t` sets the soft and hard CPU limits alike: the
// kernel then sent SIGKILL (exit 137), which leaves temporary files. The
// run lowers its soft limit a second: SIGXCPU comes first (128 + 24).
TEST(Outputs, ACpuTimeLimitEndsTheRunAsASignalDoes) {
  TempDir dir;
  const std::string scene = dir.write("slabs.json", kSlabs);
  const RunResult r = test::run_program(
      "/bin/sh", {"-c", "ulimit -t 2 && exec \"$0\" \"$@\"", OPSILA_BINARY, "render", scene, "-o",
                  dir.file("o.pfm"), "--reference", "-q"});
  EXPECT_EQ(r.exit_code, 128 + SIGXCPU) << r.err;
  EXPECT_EQ(dir.entries(), (Names{"slabs.json"}));
}

// The endless render, interrupted once it has started rendering.
TEST(Outputs, AnInterruptedRenderLeavesNothingAndExits130Or143) {
  const char* slabs = kSlabs;
  for (const int sig : {SIGINT, SIGTERM}) {
    TempDir dir;
    const std::string scene = dir.write("slabs.json", slabs);
    const std::string err = dir.file("stderr");
    pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      const int fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, 2);
      ::execl(OPSILA_BINARY, OPSILA_BINARY, "render", scene.c_str(), "-o", dir.file("o.pfm").c_str(),
              "--item-buffer", dir.file("o.npy").c_str(), "--reference", static_cast<char*>(nullptr));
      ::_exit(127);
    }
    // Wait (without a deadline on the render itself) until it renders.
    for (int i = 0; i < 6000 && test::read_file(err).find("device:") == std::string::npos; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    ASSERT_NE(test::read_file(err).find("device:"), std::string::npos);
    ::kill(pid, sig);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
    EXPECT_EQ(WEXITSTATUS(status), 128 + sig);
    EXPECT_EQ(dir.entries(), (Names{"slabs.json", "stderr"}));
  }
}

}  // namespace
}  // namespace opsila
