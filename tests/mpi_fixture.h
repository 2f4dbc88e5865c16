// The MPI tests' fixture (tests/app/mpi_*_test.cpp,
// tests/bench/mpi_bench_test.cpp): launching R ranks of opsila under
// mpiexec (Open MPI or MPICH), one process beside them, and comparing their
// outputs. Skipped, with the reason, in a build without MPI or without
// mpirun.
#pragma once

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_util.h"

namespace opsila {
namespace test_mpi {

using test::RunResult;
using test::TempDir;

#if defined(OPSILA_HAVE_MPI) && defined(OPSILA_MPIEXEC)
constexpr const char* kMpiexec = OPSILA_MPIEXEC;
#else
constexpr const char* kMpiexec = "";
#endif

// Seconds after which a run counts as hung (coreutils timeout kills it).
constexpr const char* kHangSeconds = "300";

// `mpiexec [more ranks than cores allowed] -np R`: Open MPI refuses to
// oversubscribe unless told; MPICH's launcher does it and knows no such flag.
inline std::vector<std::string> launch(int R) {
  static const bool open_mpi = [] {
    const test::RunResult v = test::run_program(
        kMpiexec, {"--version"}, {{"OMPI_ALLOW_RUN_AS_ROOT", "1"}, {"OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1"}});
    return (v.out + v.err).find("Open MPI") != std::string::npos ||
           (v.out + v.err).find("OpenRTE") != std::string::npos;
  }();
  std::vector<std::string> a = {kHangSeconds, kMpiexec};
  if (open_mpi) a.push_back("--oversubscribe");
  a.insert(a.end(), {"-np", std::to_string(R)});
  return a;
}

inline std::uint64_t facets_read(const nlohmann::json& s, std::uint64_t most, const char* why);
inline void expect_refused(const RunResult& r, const std::vector<std::string>& fragments);

struct MpiFixture : ::testing::Test {
  TempDir dir;
  void SetUp() override {
#ifndef OPSILA_HAVE_MPI
    GTEST_SKIP() << "built without MPI (no MPI library found, or -DOPSILA_MPI=OFF)";
#endif
    if (std::string(kMpiexec).empty() || ::access(kMpiexec, X_OK) != 0)
      GTEST_SKIP() << "no MPI launcher (mpirun) found at build time";
  }
  // The launcher's own session folder, one per test. Open MPI's launchers
  // share /tmp/ompi.HOST.UID and the last one to end removes it, so under
  // `ctest -j` a launcher starting then fails in its mkdir ("orte_init
  // failed"). A private TMPDIR keeps two tests' launchers apart; it is not
  // `dir`, whose entries some tests count.
  TempDir session;
  // Open MPI refuses root unless told twice; other MPIs ignore these.
  test::EnvChanges env = rank_environment(session.path());
  static test::EnvChanges rank_environment(const std::string& tmp) {
    test::EnvChanges e = {{"OMPI_ALLOW_RUN_AS_ROOT", "1"}, {"OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1"}, {"TMPDIR", tmp}};
    // Under the sanitizers: Open MPI unloads its components before
    // LeakSanitizer reports, so what they keep cannot be traced to a library
    // (frames "<unknown module>") nor suppressed by name. The ranks run with
    // ASan and UBSan but without the leak check; single-process tests keep it.
    if (const char* asan = std::getenv("ASAN_OPTIONS")) e["ASAN_OPTIONS"] = std::string(asan) + ":detect_leaks=0";
    return e;
  }
  // `opsila render ARGS` on one process, without a launcher.
  RunResult one(const std::vector<std::string>& args) {
    std::vector<std::string> a = {kHangSeconds, OPSILA_BINARY, "render"};
    a.insert(a.end(), args.begin(), args.end());
    return test::run_program("/usr/bin/timeout", a, env);
  }
  // mpiexec -np R opsila render ARGS (see launch); `more` adds programs
  // after ':' (MPMD), each a list of render arguments for one more rank.
  RunResult ranks(int R, const std::vector<std::string>& args,
                  const std::vector<std::vector<std::string>>& more = {}) {
    std::vector<std::string> a = launch(R);
    a.insert(a.end(), {OPSILA_BINARY, "render"});
    a.insert(a.end(), args.begin(), args.end());
    for (const auto& m : more) {
      a.insert(a.end(), {":", "-np", "1", OPSILA_BINARY, "render"});
      a.insert(a.end(), m.begin(), m.end());
    }
    return test::run_program("/usr/bin/timeout", a, env);
  }
  // The run ended well, and its image TAG.pfm is REFERENCE.pfm byte for byte.
  void expect_image_as(const RunResult& r, const std::string& tag, const std::string& reference) {
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(test::read_file(dir.file(tag + ".pfm")) == test::read_file(dir.file(reference + ".pfm"))) << tag;
  }
  // One rank's triangle limit lowered to `limit` (OPSILA_RANK_TRIANGLE_LIMIT)
  // and a scene over it: one process refuses it, before anything is built,
  // with one line naming every fragment, and leaves no image; two ranks
  // render it, the image REFERENCE.pfm. with(TAG): the arguments writing TAG.pfm.
  void expect_two_ranks_past_the_limit(const std::string& limit,
                                       const std::function<std::vector<std::string>(const std::string&)>& with,
                                       const std::vector<std::string>& fragments, const std::string& reference) {
    env["OPSILA_RANK_TRIANGLE_LIMIT"] = limit;
    expect_refused(one(with("alone")), fragments);
    EXPECT_FALSE(test::file_exists(dir.file("alone.pfm")));
    expect_image_as(ranks(2, with("two")), "two", reference);
  }
  std::string scene(const std::string& name) const { return std::string(OPSILA_SOURCE_DIR) + "/scenes/" + name; }
  static nlohmann::json stats(const std::string& path) { return nlohmann::json::parse(test::read_file(path)); }
  // Renders on R ranks with the arguments with("rN") gives and compares
  // with the one-process run "one": PFM, item buffer and the stats that do
  // not depend on R. `s` gets the ranks' stats.
  template <class With>
  void expect_ranks_as_one(int R, const With& with, nlohmann::json& s) {
    const std::string tag = "r" + std::to_string(R);
    const RunResult r = ranks(R, with(tag));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(test::read_file(dir.file(tag + ".pfm")) == test::read_file(dir.file("one.pfm")));
    EXPECT_TRUE(test::read_file(dir.file(tag + ".npy")) == test::read_file(dir.file("one.npy")));
    s = stats(dir.file(tag + ".json"));
    const nlohmann::json base = stats(dir.file("one.json"));
    for (const char* key : {"scene", "clusters", "rays", "levels", "memory"}) EXPECT_EQ(s.at(key), base.at(key)) << key;
  }
  // `render PATH` at 48x36 on `pes` PEs, quiet, writing TAG.pfm, TAG.npy
  // and TAG.json: the arguments for a tag.
  std::function<std::vector<std::string>(const std::string&)> every_output(const std::string& path, int pes) {
    return [this, path, pes](const std::string& tag) {
      return std::vector<std::string>{path, "--size", "48x36", "--pes", std::to_string(pes), "-q",
                                      "-o", dir.file(tag + ".pfm"), "--item-buffer", dir.file(tag + ".npy"),
                                      "--stats", dir.file(tag + ".json")};
    };
  }
  // `path` on one process, then on each count of ranks: the same image, item
  // buffer and banks (expect_ranks_as_one); `each` looks at a run's stats.
  void expect_scene_as_one(const std::string& path, int pes, const std::vector<int>& rank_counts,
                           const std::function<void(int R, const nlohmann::json&)>& each) {
    const auto with = every_output(path, pes);
    const RunResult single = one(with("one"));
    ASSERT_EQ(single.exit_code, 0) << single.err;
    for (int R : rank_counts) {
      SCOPED_TRACE(std::to_string(R) + " ranks");
      nlohmann::json s;
      expect_ranks_as_one(R, with, s);
      if (HasFatalFailure()) return;
      each(R, s);
    }
  }
  // `render PATH --balance MODE` at 48x36 on 64 PEs, writing every output.
  std::function<std::vector<std::string>(const std::string&)> balanced(const std::string& path,
                                                                       const std::string& mode) {
    return [this, path, mode](const std::string& tag) {
      return std::vector<std::string>{path, "--size", "48x36", "--pes", "64", "--balance", mode, "-q",
                                      "-o", dir.file(tag + ".pfm"), "--item-buffer", dir.file(tag + ".npy"),
                                      "--stats", dir.file(tag + ".json")};
    };
  }
  // --balance MODE on shares is one process's on 2, 3 and 4 ranks (image,
  // item buffer, banks), each rank reading about 1/R of the facets; at 64
  // PEs the balance finds clusters hotter than half a PE's share and cuts
  // them (the terrain's collectively, small objects' by their rank): more
  // clusters than by facets. `each(N, R, stats, one process's stats)` adds
  // the mode's own checks.
  void expect_balance_on_shares(
      const std::string& path, const std::string& mode,
      const std::function<void(std::uint64_t N, int R, const nlohmann::json&, const nlohmann::json&)>& each) {
    const auto with = balanced(path, mode);
    ASSERT_EQ(one(with("one")).exit_code, 0);
    const nlohmann::json base = stats(dir.file("one.json"));
    ASSERT_EQ(base.at("balance"), mode);
    ASSERT_EQ(one(balanced(path, "facets")("facets")).exit_code, 0);
    EXPECT_GT(base.at("clusters").get<int>(), stats(dir.file("facets.json")).at("clusters").get<int>());
    const std::uint64_t N = base.at("scene").at("triangles");
    for (int R : {2, 3, 4}) {
      SCOPED_TRACE(std::to_string(R) + " ranks");
      nlohmann::json s;
      expect_ranks_as_one(R, with, s);
      if (HasFatalFailure()) return;
      EXPECT_EQ(s.at("balance"), mode);
      EXPECT_EQ(facets_read(s, N / R + 320, "a share: 1/R of the facets, and at most one object more"), N);
      each(N, R, s, base);
    }
  }
  // Not quiet: no rank says it reads the whole scene.
  void expect_no_whole_scene_note(const std::string& path, const std::string& mode) {
    const RunResult loud = ranks(2, {path, "--size", "32x24", "--pes", "4", "--balance", mode, "-o",
                                     dir.file("loud.pfm")});
    ASSERT_EQ(loud.exit_code, 0) << loud.err;
    EXPECT_EQ(loud.err.find("whole scene"), std::string::npos) << loud.err;
  }
  // A bare model file streamed in windows (an OBJ, a PLY) of N triangles,
  // on 2, 3 and 4 ranks: the same image, item buffer and banks as one
  // process; each rank read about 1/R of the facets.
  void expect_windows_as_one(const std::string& path, std::uint64_t N) {
    expect_scene_as_one(path, 8, {2, 3, 4}, [&](int R, const nlohmann::json& s) {
      EXPECT_EQ(s.at("scene").at("triangles").get<std::uint64_t>(), N);
      EXPECT_EQ(facets_read(s, N / R + 4, "a window is 1/R of the fan triangles, give or take a polygon"), N);
    });
  }
};

// The facets every rank read (each at most `most`: its share), added up;
// each rank holds banks and says its peak memory.
inline std::uint64_t facets_read(const nlohmann::json& s, std::uint64_t most, const char* why) {
  std::uint64_t read = 0;
  for (const auto& rank : s.at("mpi").at("per_rank")) {
    const std::uint64_t mine = rank.at("share").at("facets_read");
    EXPECT_LE(mine, most) << why;
    EXPECT_GT(rank.at("share").at("facets_held").get<std::uint64_t>(), 0u);
    EXPECT_GT(rank.at("host_peak_bytes").get<std::uint64_t>(), 0u);
    read += mine;
  }
  return read;
}

// A scene of `entries` grids of small spheres (80 triangles, one object
// each), side by side, each grid one entry of "objects"; `files` adds that
// many included OBJ files (a box each), the one named `broken` (if any)
// with a face that names a missing vertex.
inline std::string share_scene(TempDir& dir, int entries, int files = 0, int broken = -1) {
  std::string objects;
  for (int e = 0; e < entries; ++e)
    objects += std::string(objects.empty() ? "" : ",\n") + R"({"type": "grid", "counts": [6, 6, 2], "min": [)" +
               std::to_string(4 * e) + R"(, 0, 0], "max": [)" + std::to_string(4 * e + 3) +
               R"(, 3, 1], "radius": 0.2, "subdivisions": 1, "seed": )" + std::to_string(e + 1) + "}";
  for (int k = 0; k < files; ++k) {
    const std::string name = "part" + std::to_string(k) + ".obj";
    dir.write(name, std::string("o part\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n") +
                                         (k == broken ? "f 1 2 9\n" : "f 1 2 3 4\nf 1 2 5\nf 2 3 5\n"));
    objects += ",\n" R"({"type": "obj", "file": ")" + name + R"(", "transform": {"translate": [)" +
               std::to_string(2 * k) + ", -2, 0]}}";
  }
  dir.write("share.json", "{\"objects\": [\n" + objects + "\n]}\n");
  return dir.file("share.json");
}

// Refused as bad input: exit 2 and one error line naming every fragment.
inline void expect_refused(const RunResult& r, const std::vector<std::string>& fragments) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  for (const std::string& f : fragments) EXPECT_NE(r.error_lines()[0].find(f), std::string::npos) << f << ": " << r.err;
}

}  // namespace test_mpi
}  // namespace opsila
