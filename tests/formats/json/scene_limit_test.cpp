// A scene over one process's triangle limit: the refusal says how many MPI
// ranks would take it, where ranks can (scenes/huge.json on a process that
// holds fewer triangles).
#include <gtest/gtest.h>

#include <string>

#include "formats/json/scene_file.h"
#include "test_util.h"

namespace opsila {
namespace {

std::string refusal(const std::string& objects) {
  return test::error_of([&] { load_scene_from_string(R"({"objects": [)" + objects + "]}", "s.json", "", 1000); });
}

TEST(SceneLimit, ARefusalOverOneProcesssTrianglesSaysHowManyRanksWouldTakeIt) {
  // 20 x 40 quads, 1600 triangles, after a 320-triangle sphere: 1920 of 1000.
  const std::string terrain =
      R"({"type": "sphere", "center": [0, 5, 0], "radius": 1, "subdivisions": 2},
         {"type": "terrain", "center": [0, 0, 0], "size": [10, 10], "quads": [20, 40], "height": 1})";
  const std::string e = refusal(terrain);
  EXPECT_NE(e.find("a scene may have at most 1000"), std::string::npos) << e;
#ifdef OPSILA_HAVE_MPI
  EXPECT_NE(e.find("it needs at least 2 MPI ranks (mpirun -n 2 opsila render ...)"), std::string::npos) << e;
#else
  EXPECT_EQ(e.find("MPI ranks"), std::string::npos) << e;
#endif
  // An entry that every rank builds whole: no number of ranks takes it.
  const std::string ball = refusal(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "subdivisions": 4})");
  EXPECT_NE(ball.find("a scene may have at most 1000"), std::string::npos) << ball;
  EXPECT_EQ(ball.find("MPI ranks"), std::string::npos) << ball;
}

}  // namespace
}  // namespace opsila
