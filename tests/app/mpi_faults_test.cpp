// Faults across MPI ranks: a bad flag, too many ranks, a bad device, a
// broken file, a device fault mid-frame, on one rank or on every rank at
// once, and files the ranks do not see alike: one error line, every rank
// ended, nothing written, no hang. The fixture: tests/mpi_fixture.h.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "mpi_fixture.h"
#include "ply_file.h"
#include "test_util.h"

namespace opsila {
namespace {

using namespace test_mpi;
using test::RunResult;
using test::TempDir;

// A bad flag is the same on every rank: one line, from the lowest, once.
TEST_F(MpiFixture, ABadFlagOnEveryRankIsOneLine) {
  for (const char* command : {"render", "bench"}) {
    std::vector<std::string> a = launch(3);
    a.insert(a.end(), {OPSILA_BINARY, command, scene("whitted.json"), "-o", dir.file("x.png"), "--pes", "0"});
    if (std::string(command) == "bench") a.erase(a.end() - 4, a.end() - 2);  // bench has no -o
    const RunResult r = test::run_program("/usr/bin/timeout", a, env);
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.err;
    const auto errors = r.error_lines();
    ASSERT_EQ(errors.size(), 1u) << command << ": " << r.err;
    EXPECT_EQ(errors[0].rfind("opsila: error: rank 0: --pes 0", 0), 0u) << errors[0];
    EXPECT_TRUE(dir.entries().empty()) << "an output file was left behind";
  }
}

TEST_F(MpiFixture, MoreRanksThanPesAreRefused) {
  const RunResult r = ranks(3, {scene("whitted.json"), "-o", dir.file("x.pfm"), "--size", "32x24", "--pes", "2"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto errors = r.error_lines();
  ASSERT_EQ(errors.size(), 1u) << r.err;
  EXPECT_NE(errors[0].find("3 MPI ranks for 2 PEs"), std::string::npos) << errors[0];
  EXPECT_TRUE(dir.entries().empty()) << "an output file was left behind";
}

// An output only rank 0 writes, in a folder that is not there: rank 0
// fails alone before any collective; the others met it in the wrong one
// (MPI_ERR_TRUNCATE, exit 15, no opsila line). Render and bench alike.
TEST_F(MpiFixture, AnOutputOnlyRankZeroCannotWriteIsOneLine) {
  for (const char* command : {"render", "bench"}) {
    SCOPED_TRACE(command);
    const std::string missing = dir.file("no-such-folder/x.json");
    std::vector<std::string> a = launch(3);
    a.insert(a.end(), {OPSILA_BINARY, command, scene("whitted.json"), "--size", "16x12"});
    if (std::string(command) == "bench") a.insert(a.end(), {"--quick", "--json", missing});
    else a.insert(a.end(), {"-o", dir.file("x.png"), "--stats", missing});
    const RunResult r = test::run_program("/usr/bin/timeout", a, env);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const auto errors = r.error_lines();
    ASSERT_EQ(errors.size(), 1u) << r.err;
    EXPECT_EQ(errors[0].rfind("opsila: error: rank 0: " + missing + ": cannot write", 0), 0u) << errors[0];
    EXPECT_TRUE(dir.entries().empty()) << "an output file was left behind";
  }
}

// A broken file among many, which the ranks of its share read and the
// others do not: one error line naming the file, every rank ended, no
// output left behind.
TEST_F(MpiFixture, ABrokenFileOnOneRankEndsEveryRank) {
  TempDir out;
  const std::string bad = share_scene(dir, 2, 4, 3);
  const RunResult r = ranks(3, {bad, "--size", "32x24", "--pes", "6", "-o", out.file("x.pfm")});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto errors = r.error_lines();
  ASSERT_EQ(errors.size(), 1u) << r.err;
  EXPECT_EQ(errors[0].rfind("opsila: error: rank ", 0), 0u) << errors[0];
  EXPECT_NE(errors[0].find("part3.obj"), std::string::npos) << errors[0];
  EXPECT_TRUE(out.entries().empty()) << "an output file was left behind";
}

// Ranks started unalike (mpirun's ':' programs with other flags, folders
// with their own copies of the scene) are refused before they exchange
// anything: they crashed in the exchange, or mixed two scenes in one image.
TEST_F(MpiFixture, RanksStartedUnalikeAreRefused) {
  TempDir other;
  const std::string text = R"({"objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}]})";
  dir.write("s.json", text);
  other.write("s.json", R"({"image": {"width": 40, "height": 30}, )" + text.substr(1));
  const std::vector<std::string> args = {"s.json", "--size", "32x24", "-o", dir.file("x.pfm")};
  std::vector<std::string> deeper = args;
  deeper.insert(deeper.end(), {"--depth", "3"});
  // Rank 0 in `dir` with `args`, rank 1 in `folder` with `its`.
  const auto two = [&](const std::string& folder, const std::vector<std::string>& its) {
    std::vector<std::string> a = launch(1);
    a.insert(a.end(), {"-wdir", dir.path(), OPSILA_BINARY, "render"});
    a.insert(a.end(), args.begin(), args.end());
    a.insert(a.end(), {":", "-np", "1", "-wdir", folder, OPSILA_BINARY, "render"});
    a.insert(a.end(), its.begin(), its.end());
    return test::run_program("/usr/bin/timeout", a, env);
  };
  expect_refused(two(dir.path(), deeper), {"opsila: error: rank 0: the ranks were given different arguments"});
  expect_refused(two(other.path(), args), {"opsila: error: rank 0: s.json: the ranks did not read the same file"});
  EXPECT_FALSE(test::file_exists(dir.file("x.pfm")));
}

TEST_F(MpiFixture, BadDeviceOnOneRankEndsEveryRankCleanly) {
  const std::vector<std::string> args = {scene("whitted.json"), "-o", dir.file("x.pfm"), "--size", "32x24"};
  std::vector<std::string> bad = args;
  bad.insert(bad.end(), {"--device", "no-such-device"});
  const RunResult r = ranks(2, args, {bad});  // ranks 0 and 1 fine, rank 2 bad
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto errors = r.error_lines();
  ASSERT_EQ(errors.size(), 1u) << r.err;
  EXPECT_EQ(errors[0].rfind("opsila: error: rank 2: --device no-such-device", 0), 0u) << errors[0];
  EXPECT_TRUE(dir.entries().empty()) << "an output file was left behind";
}

// A device fault on one rank in the middle of a frame, while the others
// wait for it in the exchange: one error line naming that rank, every rank
// ended (MPI_Abort), a non-zero exit, no output, no hang.
TEST_F(MpiFixture, AFaultOnOneRankMidFrameEndsEveryRank) {
  const std::vector<std::string> args = {scene("hundreds.json"), "-o", dir.file("x.pfm"), "--size", "64x48"};
  std::vector<std::string> faulty = {"OPSILA_FAULT_ROUND=2", OPSILA_BINARY, "render"};
  faulty.insert(faulty.end(), args.begin(), args.end());
  std::vector<std::string> a = launch(2);
  a.insert(a.end(), {OPSILA_BINARY, "render"});
  a.insert(a.end(), args.begin(), args.end());
  a.insert(a.end(), {":", "-np", "1", "/usr/bin/env"});  // rank 2 runs with the fault
  a.insert(a.end(), faulty.begin(), faulty.end());
  const RunResult r = test::run_program("/usr/bin/timeout", a, env);
  EXPECT_NE(r.exit_code, 0) << r.err;
  EXPECT_NE(r.exit_code, 124) << "the ranks hung";
  const auto errors = r.error_lines();
  ASSERT_EQ(errors.size(), 1u) << r.err;
  EXPECT_EQ(errors[0].rfind("opsila: error: rank 2: OpenCL: device fault at round 2", 0), 0u) << errors[0];
  EXPECT_TRUE(dir.entries().empty()) << "an output file was left behind";
}

// Every rank failing at once, each its own error: one error line, from one
// rank, whether the ranks fail while reading (the same broken file) or in
// the middle of a frame (a device fault every rank meets in one round,
// where each would otherwise print its line and abort).
TEST_F(MpiFixture, RanksFailingTogetherPrintOneLine) {
  const std::string broken = dir.write("broken.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
  for (int R : {2, 3}) {
    SCOPED_TRACE(std::to_string(R) + " ranks");
    const RunResult read = ranks(R, {broken, "--size", "32x24", "-o", dir.file("x.pfm")});
    expect_refused(read, {"broken.obj:4: vertex index 7 out of range"});
    env["OPSILA_FAULT_ROUND"] = "1";
    const RunResult r = ranks(R, {scene("hundreds.json"), "--size", "32x24", "-o", dir.file("x.pfm")});
    env.erase("OPSILA_FAULT_ROUND");
    EXPECT_EQ(r.exit_code, 3) << r.err;
    const auto errors = r.error_lines();
    ASSERT_EQ(errors.size(), 1u) << r.err;
    EXPECT_EQ(errors[0].rfind("opsila: error: rank ", 0), 0u) << errors[0];
    EXPECT_NE(errors[0].find(": OpenCL: device fault at round 1"), std::string::npos) << errors[0];
    EXPECT_FALSE(test::file_exists(dir.file("x.pfm")));
  }
}

// The model importer failing inside a library call (a fault caught by a
// signal handler, a read past its time) ends a rank at once, with no
// collective to agree on one line: every rank reads the model and printed
// its own. Rank 0 speaks; the others wait long enough for the job to end,
// so that a rank failing alone still says so. The line names the scene's
// file, line and key. The importer's fault needs Debian's assimp test models.
TEST_F(MpiFixture, AnImporterFailingInsideItsLibraryIsOneLine) {
  const std::string cob = "/usr/share/assimp/models/COB/molecule.cob";
  if (!test::file_exists(cob)) GTEST_SKIP() << "Debian package assimp-testmodels is not installed";
  const std::string cut = dir.write("cut.cob", test::read_file(cob).substr(0, 363));  // the importer faults on it
  const std::string s = dir.write("s.json", "{\"objects\": [\n{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1},"
                                            "\n{\"type\": \"model\", \"file\": \"cut.cob\"}]}");
  const RunResult r = ranks(3, {s, "--size", "32x24", "-o", dir.file("x.pfm")});
  expect_refused(r, {"opsila: error: rank 0: " + s + ":3: objects[1].file: " + cut + ": the model importer failed"});
  EXPECT_FALSE(test::file_exists(dir.file("x.pfm")));
}

TEST_F(MpiFixture, AnImporterOutOfTimeOnOneRankStillSaysSo) {
  std::string off = "OFF\n150002 150000 0\n";  // about 0.3 s for the importer
  for (int i = 0; i < 150002; ++i)
    off += std::to_string(i % 300) + " " + std::to_string(i / 300) + " " + std::to_string(i % 5) + "\n";
  for (int i = 0; i < 150000; ++i)
    off += "3 " + std::to_string(i) + " " + std::to_string(i + 1) + " " + std::to_string(i + 2) + "\n";
  const std::vector<std::string> args = {dir.write("big.off", off), "--size", "32x24", "-o", dir.file("x.pfm")};
  std::vector<std::string> a = launch(2);
  a.insert(a.end(), {OPSILA_BINARY, "render"});
  a.insert(a.end(), args.begin(), args.end());
  a.insert(a.end(), {":", "-np", "1", "/usr/bin/env", "OPSILA_IMPORT_TIMEOUT=0", OPSILA_BINARY, "render"});
  a.insert(a.end(), args.begin(), args.end());  // rank 2 gives the importer no time
  const RunResult r = test::run_program("/usr/bin/timeout", a, env);
  EXPECT_NE(r.exit_code, 0) << r.err;
  EXPECT_NE(r.exit_code, 124) << "the ranks hung";
  const auto errors = r.error_lines();
  ASSERT_EQ(errors.size(), 1u) << r.err;
  EXPECT_EQ(errors[0].rfind("opsila: error: rank 2: " + args[0] + ": the model importer did not finish", 0), 0u)
      << errors[0];
  EXPECT_FALSE(test::file_exists(dir.file("x.pfm")));
}

// Ranks that do not see the same model file (one started in another
// folder, as on machines with their own copies, or a file rewritten while
// they stream it): refused with one line naming the file, before any
// facet is exchanged, where they went on to exchange what did not match.
TEST_F(MpiFixture, RanksThatReadDifferentFilesAreRefused) {
  TempDir other;
  for (const std::string name : {"model.obj", "model.ply"}) {
    SCOPED_TRACE(name);
    for (TempDir* d : {&dir, &other}) {
      test::PlyFile p = test::ply_grid(d == &dir ? 30 : 34, 20, 0);
      if (name == "model.ply") {
        test::write_ply(d->file(name), p);
        continue;
      }
      std::string obj;
      for (const auto& v : p.vertices) obj += "v " + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " +
                                              std::to_string(v[2]) + "\n";
      for (const auto& f : p.faces) {
        if (f.size() < 3) continue;
        obj += "f";
        for (long long i : f) obj += " " + std::to_string(i + 1);
        obj += "\n";
      }
      d->write(name, obj);
    }
    const std::vector<std::string> args = {OPSILA_BINARY, "render", name, "--size", "32x24", "--pes", "4",
                                           "-o", dir.file("x.pfm")};
    std::vector<std::string> a = launch(2);
    a.insert(a.end(), {"-wdir", dir.path()});
    a.insert(a.end(), args.begin(), args.end());
    a.insert(a.end(), {":", "-np", "1", "-wdir", other.path()});  // rank 2 sees the other copy
    a.insert(a.end(), args.begin(), args.end());
    const RunResult r = test::run_program("/usr/bin/timeout", a, env);
    expect_refused(r, {"opsila: error: rank 0: " + name + ": the ranks did not read the same file"});
    EXPECT_FALSE(test::file_exists(dir.file("x.pfm")));
  }
}

}  // namespace
}  // namespace opsila
