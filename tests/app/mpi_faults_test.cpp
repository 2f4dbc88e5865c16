// MPI runs beside tests/app/mpi_test.cpp (same fixture, tests/mpi_fixture.h):
// PLY triangle strips streamed by ranks, and the faults several ranks meet
// at once, or a file the ranks do not see alike, each one error line.
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

#ifdef OPSILA_HAVE_ASSIMP
// A bare PLY of strips: each rank streams its window of the strips'
// triangles; the image, item buffer and banks of one process, which reads
// it with the same stream.
TEST_F(MpiFixture, PlyStripsReadInWindowsAreTheSameAsOneProcess) {
  test::PlyFile p = test::ply_grid(21, 11, 0);
  p.faces.clear();
  p.face_element = false;
  std::vector<std::vector<long long>> faces;
  p.strips = test::grid_strips(21, 11, faces);
  const std::string path = dir.file("strips.ply");
  test::write_ply(path, p);
  expect_windows_as_one(path, faces.size());
}
#endif

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
