// `mpirun -np R opsila bench`: every rank renders its PEs, rank 0 alone
// reports every rank's figures and the traffic between them, on a whole
// scene and on one read in shares; too many ranks are refused once. The
// fixture: tests/mpi_fixture.h.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mpi_fixture.h"
#include "test_util.h"

namespace opsila {
namespace {

using namespace test_mpi;
using test::RunResult;

// `mpirun -np R opsila bench`: every rank renders its PEs, rank 0 alone
// reports: each rank's figures, the rank x rank traffic (every descriptor
// sent is received, and the per-level count from the PE traffic agrees), the
// exchange's share of the frame. Baselines and the scatter curve are left out.
TEST_F(MpiFixture, BenchOnSeveralRanksReportsEveryRank) {
  std::vector<std::string> a = launch(3);
  a.insert(a.end(), {OPSILA_BINARY, "bench", scene("whitted.json"), "--quick", "--size", "64x48", "--json",
                     dir.file("b.json"), "--csv", dir.file("csv")});
  const RunResult r = test::run_program("/usr/bin/timeout", a, env);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // One report (rank 0's), every rank's device named.
  EXPECT_EQ(test::count_of(r.out, "opsila bench: "), 1u) << r.out;
  EXPECT_NE(r.out.find("MPI ranks: 3"), std::string::npos) << r.out;
  for (int k = 0; k < 3; ++k)
    EXPECT_NE(r.err.find("device: rank " + std::to_string(k) + " of 3"), std::string::npos) << r.err;
  const nlohmann::json j = stats(dir.file("b.json"));
  EXPECT_EQ(j.at("ranks"), 3);
  const nlohmann::json& mpi = j.at("mpi");
  ASSERT_EQ(mpi.at("per_rank").size(), 3u);
  EXPECT_TRUE(mpi.at("exchange_balanced").get<bool>());
  const auto sent = mpi.at("descriptors_sent").get<std::uint64_t>();
  EXPECT_GT(sent, 0u);
  EXPECT_EQ(sent, mpi.at("descriptors_received").get<std::uint64_t>());
  std::uint64_t by_level = 0;
  for (const auto& n : mpi.at("descriptors_between_ranks_by_level")) by_level += n.get<std::uint64_t>();
  EXPECT_EQ(by_level, sent) << "the PE traffic and the ranks' own counts disagree";
  for (const char* key : {"exchange_share", "exposed_share", "mpi_share"}) {
    EXPECT_GT(mpi.at(key).get<double>(), 0.0) << key;
    EXPECT_LE(mpi.at(key).get<double>(), 1.0) << key;
  }
  EXPECT_LE(mpi.at("exposed_share").get<double>(), mpi.at("exchange_share").get<double>());
  for (const auto& rank : mpi.at("per_rank")) {
    EXPECT_GT(rank.at("device_bytes").get<std::uint64_t>(), 0u);
    EXPECT_GT(rank.at("host_peak_bytes").get<std::uint64_t>(), 0u);
  }
  EXPECT_TRUE(j.at("baselines").empty());
  EXPECT_TRUE(j.at("scatter").empty());
  EXPECT_TRUE(j.at("targets").at("opsila_vs_megakernel").is_null());
  EXPECT_TRUE(test::file_exists(dir.file("csv/ranks.csv")));
  EXPECT_EQ(test::count_of(test::read_file(dir.file("csv/ranks.csv")), "\n"), 4u);  // header + 3 ranks
  EXPECT_TRUE(test::file_exists(dir.file("csv/rank_traffic.csv")));
  EXPECT_FALSE(test::file_exists(dir.file("csv/scatter.csv")));
}

// `mpirun -np R opsila bench` reads a JSON scene in shares, as render does
// (with its default --balance, measured, as on one process): every rank's report says
// what it read (about 1/R of the facets) and held, and its preparation
// times; the banks, rays and per-rank shares are those `opsila render`
// builds on as many ranks; the whole-scene baselines are left out, saying why.
TEST_F(MpiFixture, BenchReadsSharesAndReportsEveryRank) {
  const std::string path = share_scene(dir, 6, 5);
  const std::vector<std::string> view = {path, "--size", "64x48", "--pes", "12", "-q"};
  std::vector<std::string> render_args = view;
  render_args.insert(render_args.end(), {"--balance", "measured", "-o", dir.file("r.pfm"), "--stats", dir.file("r.json")});
  const int R = 3;
  const RunResult rendered = ranks(R, render_args);
  ASSERT_EQ(rendered.exit_code, 0) << rendered.err;
  std::vector<std::string> a = launch(R);
  a.insert(a.end(), {OPSILA_BINARY, "bench"});
  a.insert(a.end(), view.begin(), view.end());
  a.insert(a.end(), {"--quick", "--json", dir.file("b.json"), "--csv", dir.file("csv")});
  const RunResult r = test::run_program("/usr/bin/timeout", a, env);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("scene read in shares"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("not measured: the baselines"), std::string::npos) << r.out;
  const nlohmann::json j = stats(dir.file("b.json")), s = stats(dir.file("r.json"));
  const std::uint64_t N = s.at("scene").at("triangles");
  EXPECT_EQ(j.at("balance"), "measured") << "the bench's default, on ranks as on one process";
  EXPECT_EQ(j.at("scene").at("triangles"), N) << "the whole scene's count, not rank 0's share";
  EXPECT_EQ(j.at("scene").at("clusters"), s.at("clusters"));
  for (const char* key : {"bank_bytes", "texture_bytes", "global_bytes", "replicated_bytes"})
    EXPECT_EQ(j.at("memory").at(key), s.at("memory").at(key)) << key;
  for (const char* kind : {"primary", "secondary", "shadow"})
    EXPECT_EQ(j.at("render").at("rays_by_kind").at(kind), s.at("rays").at(kind)) << kind;
  EXPECT_TRUE(j.at("render").at("deterministic").get<bool>());
  const nlohmann::json& per_rank = j.at("mpi").at("per_rank");
  ASSERT_EQ(per_rank.size(), std::size_t(R));
  std::uint64_t read = 0;
  for (int k = 0; k < R; ++k) {
    const nlohmann::json& share = per_rank.at(k).at("share");
    const nlohmann::json& rendered_share = s.at("mpi").at("per_rank").at(k).at("share");
    EXPECT_LE(share.at("facets_read").get<std::uint64_t>(), N / R + 80) << "rank " << k;
    EXPECT_EQ(share.at("facets_read"), rendered_share.at("facets_read")) << "rank " << k;
    EXPECT_EQ(share.at("facets_held"), rendered_share.at("facets_held")) << "rank " << k;
    // The pilots ran on the shares: the share kept beside a pilot's banks.
    EXPECT_GT(share.at("pilot_facets_held").get<std::uint64_t>(), share.at("facets_read").get<std::uint64_t>());
    for (const char* stage : {"read_seconds", "partition_seconds", "exchange_seconds", "bank_seconds"})
      EXPECT_GE(share.at(stage).get<double>(), 0.0) << stage;
    EXPECT_GT(per_rank.at(k).at("host_peak_bytes").get<std::uint64_t>(), 0u);
    EXPECT_GT(per_rank.at(k).at("render_seconds").get<double>(), 0.0);
    read += share.at("facets_read").get<std::uint64_t>();
  }
  EXPECT_EQ(read, N);
  EXPECT_TRUE(j.at("baselines").empty());
  EXPECT_NE(j.at("baselines_left_out").get<std::string>().find("whole scene"), std::string::npos);
  // ranks.csv: a header and one row per rank, with the share's figures.
  const std::string csv = test::read_file(dir.file("csv/ranks.csv"));
  EXPECT_NE(csv.find(",facets_read,facets_held,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",pilot_facets_held\n"), std::string::npos) << csv;
  EXPECT_EQ(test::count_of(csv, "\n"), std::size_t(R) + 1);
  EXPECT_EQ(test::count_of(csv, ",,"), 0u) << "a rank's share figures are missing: " << csv;
}

// More ranks than PEs: one error line, nothing written.
TEST_F(MpiFixture, BenchWithMoreRanksThanPesIsRefusedOnce) {
  std::vector<std::string> a = launch(3);
  a.insert(a.end(), {OPSILA_BINARY, "bench", scene("whitted.json"), "--quick", "--pes", "2", "--json",
                     dir.file("b.json")});
  const RunResult r = test::run_program("/usr/bin/timeout", a, env);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto errors = r.error_lines();
  ASSERT_EQ(errors.size(), 1u) << r.err;
  EXPECT_NE(errors[0].find("3 MPI ranks for 2 PEs"), std::string::npos) << errors[0];
  EXPECT_TRUE(dir.entries().empty()) << "an output file was left behind";
}

}  // namespace
}  // namespace opsila
