// MPI runs beside tests/cli/mpi_test.cpp (same fixture, tests/mpi_fixture.h):
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

}  // namespace
}  // namespace opsila
