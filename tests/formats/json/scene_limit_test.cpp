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
  // Past 2^31 - 1 (ids are 32-bit) neither ranks nor memory take it: no advice.
  const std::string huge = test::error_of([&] {
    load_scene_from_string(R"({"objects": [{"type": "terrain", "size": [10, 10], "quads": [50000, 50000]}]})",
                           "s.json", "", TriangleLimit{kMaxTriangles});
  });
  EXPECT_NE(huge.find("a scene may have at most 2147483647"), std::string::npos) << huge;
  EXPECT_EQ(huge.find("MPI ranks"), std::string::npos) << huge;
  EXPECT_EQ(huge.find("--host-memory"), std::string::npos) << huge;
}

// Line ends of the classic Mac OS (a carriage return alone) count as line
// ends in every message, as CRLF and LF do.
TEST(SceneText, ALoneCarriageReturnEndsALine) {
  const auto error = [](const std::string& text) {
    return test::error_of([&] { load_scene_from_string(text, "t.json", "", 1000); });
  };
  const std::string objects = R"("objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}])";
  for (const char* end : {"\n", "\r\n", "\r"}) {
    SCOPED_TRACE(std::string(end) == "\r" ? "CR" : "LF");
    const std::string e = std::string(end);
    EXPECT_EQ(error("{" + e + objects + "," + e + e + R"("depth": 0})"), "t.json:4: depth: must be in 1..31, not 0");
    EXPECT_EQ(error("{" + e + objects + "," + e + e + R"("depth": 1,})").rfind("t.json:4:", 0), 0u);
  }
}

// "comment" is allowed in every object (scenes/FORMAT.md), the materials'
// too, where it names no material; an object's "name" is a string.
TEST(SceneText, ACommentAmongMaterialsAndANameThatIsNoString) {
  const std::string sphere = R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "subdivisions": 1, "material": "m")";
  const Scene s = load_scene_from_string(
      R"({"materials": {"comment": "mine", "m": {"Kd": 0.5}}, "objects": [)" + sphere + "}]}", "t.json", "", 1000);
  int named_m = 0;
  for (const MaterialDesc& m : s.materials) {
    EXPECT_NE(m.name, "comment");
    named_m += m.name == "m";
  }
  EXPECT_EQ(named_m, 1);
  EXPECT_EQ(test::error_of([&] {
              load_scene_from_string(R"({"materials": {"m": {}}, "objects": [)" + sphere + R"(, "name": 5}]})",
                                     "t.json", "", 1000);
            }),
            "t.json:1: objects[0].name: expected a string, not a number");
}

}  // namespace
}  // namespace opsila
