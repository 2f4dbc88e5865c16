// Instances under mpirun: every rank reads them all (they are not dealt),
// deals them to PEs as one process does and banks its own PEs' (model
// copies, instance BVHs): the same image, item buffer and banks on one
// process and on 2, 3 and 4 ranks, beside a terrain made in windows, by
// facets and by sampled work.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mpi_fixture.h"
#include "test_util.h"

namespace opsila {
namespace {

using namespace test_mpi;

const char* const kForest = R"({"camera": {"eye": [0, 7, 13], "look_at": [0, 0, -1]},
  "lights": [{"position": [5, 10, 6], "intensity": 0.8}, {"position": [-6, 8, 2], "intensity": 0.4}],
  "materials": {"mirror": {"Kd": 0.05, "kr": 0.9, "Ns": 80}, "red": {"Kd": [0.8, 0.2, 0.1], "Ks": 0.3, "Ns": 30},
                "glass": {"Kd": 0.02, "kr": 0.1, "kt": 0.9, "Ni": 1.5, "Ns": 120}},
  "objects": [
    {"type": "terrain", "size": [24, 24], "quads": [60, 60], "height": 1.5, "center": [0, -1, 0]},
    {"type": "instances", "model": {"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5, "subdivisions": 2,
                                    "material": "red"},
     "grid": {"counts": [12, 1, 9], "min": [-8, 0.5, -8], "max": [8, 0.5, 5], "jitter": 0.6, "scale": [0.5, 1.3],
              "rotate_y": [0, 360], "seed": 5}},
    {"type": "instances", "model": {"type": "box", "center": [0, 0.5, 0], "size": 1, "material": "mirror"},
     "transforms": [{"translate": [2, 0.5, 3]}, {"scale": [1, 3, 0.5], "rotate": [0, 30, 0], "translate": [-3, 0.5, 1]},
                    {"scale": 0.7, "rotate": [20, 0, 10], "translate": [0, 2.5, 2]}]},
    {"type": "sphere", "center": [4, 2, 4], "radius": 1, "material": "glass"}]})";

TEST_F(MpiFixture, InstancesAcrossRanks) {
  const std::string path = dir.write("forest.json", kForest);
  for (const char* balance : {"facets", "work"}) {
    SCOPED_TRACE(std::string("balance ") + balance);
    const auto with = [&](const std::string& tag) {
      return std::vector<std::string>{path, "--size", "96x72", "--pes", "16", "--balance", balance, "-q",
                                      "-o", dir.file(tag + ".pfm"), "--item-buffer", dir.file(tag + ".npy"),
                                      "--stats", dir.file(tag + ".json")};
    };
    const RunResult single = one(with("one"));
    ASSERT_EQ(single.exit_code, 0) << single.err;
    const nlohmann::json st = stats(dir.file("one.json"));
    EXPECT_EQ(st["scene"]["instances"]["count"], 111);
    for (int R : {2, 3, 4}) {
      SCOPED_TRACE(std::to_string(R) + " ranks");
      nlohmann::json s;
      expect_ranks_as_one(R, with, s);
    }
  }
}

}  // namespace
}  // namespace opsila
