// The bench's outputs are all or nothing, its report on standard output
// included: a report that cannot be written leaves the saved files as they
// were (the --json file had been replaced before the report failed).
#include <gtest/gtest.h>
#include <unistd.h>

#include <string>

#include "test_util.h"

namespace opsila {
namespace {

TEST(BenchOutputs, AReportThatCannotBeWrittenLeavesTheFilesAsTheyWere) {
  if (access("/dev/full", W_OK) != 0) GTEST_SKIP() << "no /dev/full to write to";
  test::TempDir dir;
  const std::string json = dir.write("old.json", "{\"saved\": true}\n");
  const std::string scene = std::string(OPSILA_SOURCE_DIR) + "/scenes/whitted.json";
  std::vector<std::string> args = {"bench", scene,   "--size",     "16x12", "--quick", "--scatter-max", "4",
                                   "--balance", "facets", "--json", json, "--csv", dir.file("csv")};
  if (const char* device = std::getenv("OPSILA_TEST_DEVICE")) args.insert(args.end(), {"--device", device});
  const test::RunResult r = test::run_program(OPSILA_BINARY, args, {}, "/dev/full");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("standard output: write failed (No space left on device)"), std::string::npos) << r.err;
  EXPECT_EQ(test::read_file(json), "{\"saved\": true}\n");
  EXPECT_FALSE(test::file_exists(dir.file("csv")));
}

}  // namespace
}  // namespace opsila
