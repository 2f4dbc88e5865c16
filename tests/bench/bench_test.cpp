// The benchmark's baselines and outputs: the replicated megakernel renders
// the OPSILA image, every implementation counts the same rays, the host
// scatter places descriptors exactly as the scatter kernels do, and
// `opsila bench --quick` writes the JSON that scripts rely on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <thread>

#include <nlohmann/json.hpp>

#include "prepare/prepare_banks.h"
#include "bench/bench.h"
#include "bench/compare.h"
#include "frame/host_scatter.h"
#include "partition/partition.h"
#include "formats/json/scene_file.h"
#include "reference/reference.h"
#include "frame/renderer.h"
#include "exchange_check.h"
#include "test_device.h"
#include "scene/scene.h"
#include "test_scenes.h"
#include "test_util.h"

namespace opsila {
namespace {

ClRuntime& runtime() { return test::shared_runtime(); }

RenderResult render_opsila(const Scene& s, int pes) {
  RenderSettings rs;
  rs.num_pes = pes;
  return render(s, rs, runtime());
}

using test::item_agreement;

TEST(Bench, MegakernelImageEqualsOpsilaImage) {
  const Scene s = test::mirror_glass_scene(96, 5);
  const RenderResult opsila = render_opsila(s, 16);
  const BaselineImage mega = render_megakernel(s, runtime());
  ASSERT_EQ(mega.rgb.size(), opsila.rgb.size());
  EXPECT_GE(test::clamped_psnr(mega.rgb, opsila.rgb), 50.0);
  EXPECT_GE(item_agreement(mega.item_buffer, opsila.item_buffer), 0.999);
  // Same shading and the same fixed-point sums: nearly every pixel is identical.
  std::size_t same = 0;
  for (std::size_t i = 0; i < mega.rgb.size(); i += 3)
    same +=
        mega.rgb[i] == opsila.rgb[i] && mega.rgb[i + 1] == opsila.rgb[i + 1] && mega.rgb[i + 2] == opsila.rgb[i + 2];
  EXPECT_GE(double(same) / double(mega.rgb.size() / 3), 0.99);
}

TEST(Bench, MegakernelTilesDoNotChangeTheImage) {
  const Scene s = test::mirror_glass_scene(48, 4);
  const BaselineImage whole = render_megakernel(s, runtime());
  const BaselineImage tiled = render_megakernel(s, runtime(), 500);
  EXPECT_EQ(whole.rgb, tiled.rgb);
  EXPECT_EQ(whole.rays.total(), tiled.rays.total());
}

// Without its test counters (the bench's timed frames) the megakernel gives
// the same image, item buffer and rays and counts no test; counting again,
// its tests are those of a fresh megakernel's.
TEST(Bench, MegakernelWithoutCountersGivesTheSameImage) {
  const Scene s = test::mirror_glass_scene(48, 4);
  const BaselineImage counted = render_megakernel(s, runtime());
  ASSERT_GT(counted.box_tests, 0u);
  ASSERT_GT(counted.triangle_tests, 0u);
  Megakernel mega(s, runtime(), 500);
  mega.count_work(false);
  const BaselineImage uncounted = mega.frame();
  EXPECT_EQ(uncounted.rgb, counted.rgb);
  EXPECT_EQ(uncounted.item_buffer, counted.item_buffer);
  EXPECT_TRUE(uncounted.rays.same_rays(counted.rays));
  EXPECT_EQ(uncounted.box_tests, 0u);
  EXPECT_EQ(uncounted.triangle_tests, 0u);
  mega.count_work(true);
  const BaselineImage again = mega.frame();
  EXPECT_EQ(again.rgb, counted.rgb);
  EXPECT_EQ(again.box_tests, counted.box_tests);
  EXPECT_EQ(again.triangle_tests, counted.triangle_tests);
}

// A megakernel prepared once renders every frame alike: its buffers, kept
// between frames, are written whole by each.
TEST(Bench, MegakernelFramesReuseItsBuffersAlike) {
  const Scene s = test::mirror_glass_scene(48, 4);
  const BaselineImage once = render_megakernel(s, runtime());
  Megakernel mega(s, runtime(), 500);
  for (int frame = 0; frame < 2; ++frame) {
    const BaselineImage again = mega.frame();
    EXPECT_EQ(again.rgb, once.rgb) << frame;
    EXPECT_EQ(again.item_buffer, once.item_buffer) << frame;
    EXPECT_EQ(again.rays.total(), once.rays.total()) << frame;
    EXPECT_EQ(again.box_tests, once.box_tests) << frame;
    EXPECT_GT(again.kernel_seconds, 0.0) << frame;
  }
  // Into an image that already holds another frame (the bench's repeats):
  // every field is rewritten, none accumulates.
  BaselineImage reused = once;
  std::fill(reused.rgb.begin(), reused.rgb.end(), -1.0f);
  std::fill(reused.item_buffer.begin(), reused.item_buffer.end(), 7);
  for (int frame = 0; frame < 2; ++frame) {
    mega.frame(reused);
    EXPECT_EQ(reused.rgb, once.rgb) << frame;
    EXPECT_EQ(reused.item_buffer, once.item_buffer) << frame;
    EXPECT_EQ(reused.rays.total(), once.rays.total()) << frame;
    EXPECT_EQ(reused.triangle_tests, once.triangle_tests) << frame;
    EXPECT_EQ(reused.box_tests, once.box_tests) << frame;
  }
}

// The megakernel's miss-cheap root (kernels/lib/bvh.cl, scene_nearest): a
// camera ray that misses the union of the root's child boxes is not walked,
// and its root's box tests are counted as the walk counts them, one per slot
// in use. Here every ray misses: the scene lies at z <= 6, behind the eye.
TEST(Bench, MegakernelRaysMissingTheSceneCountTheRootsTests) {
  Scene s = test::mirror_glass_scene(32, 4);
  s.camera.look_at = {0, 3, 16};  // the eye is at z = 8
  const BaselineImage mega = render_megakernel(s, runtime());
  const BankedScene bs = partition_scene(s, 1);
  const BankNode& root = bs.nodes[std::size_t(bs.pes[0].node_begin)];
  std::uint64_t slots = 0;
  for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) slots += root.count[k] >= 0;
  ASSERT_GT(slots, 1u);
  EXPECT_EQ(mega.box_tests, std::uint64_t(s.width) * s.height * slots);
  EXPECT_EQ(mega.triangle_tests, 0u);
  EXPECT_EQ(mega.rgb, render_opsila(s, 16).rgb);
}

// The traversal alone traces exactly the megakernel's rays: its primary and
// secondary rays as nearest-hit rays, its shadow rays as any-hit rays (an
// even sample grid's centre ray, not counted as a ray, is left out).
TEST(Bench, TraversalAloneTracesTheMegakernelsRays) {
  for (int spp : {1, 4}) {
    Scene s = test::mirror_glass_scene(40, 4);
    s.spp = spp;
    const BaselineImage mega = render_megakernel(s, runtime());
    const TraversalAlone t = measure_traversal_alone(s, runtime(), 0, 2, 500);
    ASSERT_TRUE(t.present) << t.skipped;
    ASSERT_GT(mega.rays.secondary, 0u);
    EXPECT_EQ(t.nearest_rays, mega.rays.primary + mega.rays.secondary) << spp;
    EXPECT_EQ(t.any_rays, mega.rays.shadow) << spp;
    EXPECT_EQ(t.seconds_all.size(), 2u);
    EXPECT_DOUBLE_EQ(t.seconds, t.nearest_seconds + t.any_seconds);
  }
}

TEST(Bench, RayCountsAgreeAcrossImplementations) {
  const Scene s = test::mirror_glass_scene(80, 5);
  const RayCounts st = render_opsila(s, 8).rays;
  const BaselineImage mega = render_megakernel(s, runtime());
  const ImageResult host = render_reference(s, 2);
  ASSERT_GT(st.secondary, 0u);
  ASSERT_GT(st.shadow, 0u);
  EXPECT_EQ(mega.rays.primary, st.primary);
  EXPECT_EQ(mega.rays.secondary, st.secondary);
  EXPECT_EQ(mega.rays.shadow, st.shadow);
  EXPECT_EQ(host.rays.primary, st.primary);
  EXPECT_EQ(host.rays.secondary, st.secondary);
  EXPECT_EQ(host.rays.shadow, st.shadow);
  if (embree_available()) {
    // Embree finds its own hit distances (not the watertight test's), so a
    // ray grazing an edge may take another path: counts agree to 0.5%.
    const BaselineImage e = render_embree(s, 2);
    EXPECT_EQ(e.rays.primary, st.primary);
    EXPECT_NEAR(double(e.rays.secondary), double(st.secondary), 0.005 * st.secondary + 2);
    EXPECT_NEAR(double(e.rays.shadow), double(st.shadow), 0.005 * st.shadow + 2);
    EXPECT_GE(test::clamped_psnr(e.rgb, render_opsila(s, 8).rgb), 35.0);
  }
}

// The Embree baseline shades what OPSILA shades: texture maps, smooth
// normals and k x k samples, on the gallery's scenes at a small size.
void expect_embree_agrees(const std::string& scene_file, int spp) {
  if (!embree_available()) GTEST_SKIP() << "built without Embree";
  const std::string models = "/usr/share/assimp/models";
  const std::string path = std::string(OPSILA_SOURCE_DIR) + "/scenes/" + scene_file;
  if (test::read_file(path).find(models) != std::string::npos && !test::file_exists(models))
    GTEST_SKIP() << scene_file << " needs Debian's assimp-testmodels";
  Scene s = load_scene(path);
  s.width = 64;
  s.height = 48;
  s.spp = spp;
  const RenderResult opsila = render_opsila(s, 16);
  const BaselineImage e = render_embree(s, 2);
  EXPECT_GE(test::clamped_psnr(e.rgb, opsila.rgb), 40.0) << scene_file << ", " << spp << " spp";
  EXPECT_EQ(e.rays.primary, opsila.rays.primary);
  EXPECT_GE(item_agreement(e.item_buffer, opsila.item_buffer), 0.99);
}

TEST(Bench, EmbreeAgreesOnTexturedScene) { expect_embree_agrees("textured.json", 1); }
TEST(Bench, EmbreeAgreesOnTexturedSceneWithSamples) { expect_embree_agrees("textured.json", 4); }
TEST(Bench, EmbreeAgreesOnSmoothScene) { expect_embree_agrees("smooth.json", 1); }
TEST(Bench, EmbreeAgreesOnSmoothSceneWithSamples) { expect_embree_agrees("smooth.json", 4); }

// ScatterPass over a pool alone (no SPMD outputs) of a frame of depth 5,
// and what it made: the plan, every bank slot and what waits.
constexpr int kScatterDepth = 5;
struct PoolScatter {
  std::vector<cl_int> bank_begin, bank_count, counts;  // counts = {waiting, placed, groups}
  HostDescriptors banks, next;
};
PoolScatter scatter_pool(const HostDescriptors& src, int pes, int slots, int cap, int group_size, bool throttle) {
  ClRuntime& rt = runtime();
  const std::size_t bank_slots = std::size_t(slots) + std::size_t(pes) * group_size;
  DescriptorSet pool, banks, next;
  pool.allocate(rt, src.size(), "test pool");
  banks.allocate(rt, bank_slots, "test banks");
  next.allocate(rt, src.size(), "test next");
  pool.write(rt, src, 0, kScatterDepth);
  ScatterPass scatter(rt, pes);
  ScatterPass::Args a = ScatterPass::pool_only(pool, src.size(), banks, next, slots, group_size);
  a.cap = cap;
  a.throttle = throttle;
  test::run_exchange_pass(rt, scatter, a);
  PoolScatter r;
  r.bank_begin = test::from_device<cl_int>(rt, scatter.bank_ranges.begin, pes);
  r.bank_count = test::from_device<cl_int>(rt, scatter.bank_ranges.count, pes);
  r.counts = test::from_device<cl_int>(rt, scatter.counts, 3);
  r.banks = banks.read(rt, bank_slots);
  r.next = next.read(rt, std::size_t(r.counts[0]));
  return r;
}

// Host scatter and ScatterPass on the same input, with holes and overflow:
// the same plan, and every lane of every bank slot and waiting entry. A
// fraction `shadows` of the rays end their tree (shadow rays);
// `throttle` as when more wait than the frame planned for.
void expect_same_placement(std::size_t length, int pes, int slots, int cap, int group_size, double holes,
                           unsigned seed, double shadows = 0.0, bool throttle = false) {
  SCOPED_TRACE("length " + std::to_string(length) + ", seed " + std::to_string(seed));
  const HostDescriptors src = random_descriptors(length, pes, holes, seed, shadows);
  const std::size_t bank_slots = std::size_t(slots) + std::size_t(pes) * group_size;
  HostDescriptors hb(bank_slots), hn(length);
  std::vector<std::size_t> scratch;
  const HostScatterResult hr =
      host_scatter(src, pes, slots, cap, group_size, kScatterDepth, throttle, hb, hn, scratch);
  const PoolScatter d = scatter_pool(src, pes, slots, cap, group_size, throttle);
  ASSERT_EQ(d.bank_begin, hr.bank_begin);
  ASSERT_EQ(d.bank_count, hr.bank_count);
  ASSERT_EQ(std::size_t(d.counts[0]), hr.waiting);
  ASSERT_EQ(std::size_t(d.counts[1]), hr.placed);
  ASSERT_EQ(d.counts[2], hr.groups);
  ASSERT_GT(hr.placed, 0u);
  for (int q = 0; q < pes; ++q)
    for (int r = 0; r < d.bank_count[q]; ++r) {
      const std::size_t at = std::size_t(d.bank_begin[q]) + r;
      ASSERT_TRUE(test::same_record(d.banks[at], hb[at])) << "bank " << q << " slot " << r;
      ASSERT_EQ(desc_dest(d.banks[at]), q);
    }
  for (std::size_t k = 0; k < hr.waiting; ++k) ASSERT_TRUE(test::same_record(d.next[k], hn[k])) << "pool slot " << k;
}

TEST(Bench, HostScatterPlacesLikeTheScatterKernels) {
  expect_same_placement(16, 16, 32, 0, 1, 0.0, 1);
  expect_same_placement(5000, 16, 3200, 0, 16, 0.3, 2);     // overflow: ~3500 valid, 3200 slots
  expect_same_placement(32767, 16, 65536, 0, 64, 0.1, 3);   // no overflow
  expect_same_placement(3000, 1, 100, 0, 64, 0.5, 4);
  expect_same_placement(4000, 64, 64, 0, 1, 0.2, 5);
  expect_same_placement(4000, 16, 4000, 32, 16, 0.2, 6);    // two work-groups per PE at most
  // Shadow rays (they end their tree) go first; throttled, only they go.
  expect_same_placement(5000, 16, 3200, 0, 16, 0.3, 7, 0.25);
  expect_same_placement(5000, 16, 3200, 0, 16, 0.3, 8, 0.25, true);
  expect_same_placement(4000, 16, 4000, 32, 16, 0.2, 9, 0.5, true);
  expect_same_placement(4000, 16, 4000, 32, 16, 0.2, 10, 0.0, true);  // none ends its tree: not throttled
}

// The order that bounds what waits (kernels/scatter.cl), on the kernels'
// own banks: per PE, the rays that end their tree (shadow rays here) take
// the first slots; throttled, the banks take only them while any waits,
// and with none waiting the round is as if not throttled.
TEST(Bench, ScatterTakesRaysThatEndTheirTreeFirst) {
  constexpr int kPes = 8, kSlots = 800, kGroup = 16;
  constexpr std::size_t kLength = 3000;
  // Per PE, per bank slot: whether it holds a shadow ray.
  auto banks_of = [&](double shadows, bool throttle, int* placed) {
    const PoolScatter d = scatter_pool(random_descriptors(kLength, kPes, 0.1, 21, shadows), kPes, kSlots, 0, kGroup,
                                       throttle);
    *placed = d.counts[1];
    std::vector<std::vector<bool>> ends(kPes);
    for (int q = 0; q < kPes; ++q)
      for (int r = 0; r < d.bank_count[q]; ++r)
        ends[q].push_back(OPSILA_META_KIND(desc_meta(d.banks[std::size_t(d.bank_begin[q]) + r])) ==
                          OPSILA_KIND_SHADOW);
    return ends;
  };
  int placed = 0, shadows = 0;
  for (const auto& bank : banks_of(0.15, false, &placed)) {
    ASSERT_TRUE(std::is_sorted(bank.begin(), bank.end(), std::greater<bool>())) << "a radiance ray before a shadow ray";
    shadows += static_cast<int>(std::count(bank.begin(), bank.end(), true));
  }
  EXPECT_EQ(placed, kSlots);
  EXPECT_GT(shadows, 0);
  EXPECT_LT(shadows, placed);
  int throttled = 0;
  for (const auto& bank : banks_of(0.15, true, &throttled))
    EXPECT_EQ(std::count(bank.begin(), bank.end(), false), 0) << "a throttled bank took a radiance ray";
  EXPECT_GT(throttled, 0);
  EXPECT_LT(throttled, kSlots);  // about 0.15 x 0.9 x 3000 = 405 shadow rays
  int unthrottled = 0;
  banks_of(0.0, true, &unthrottled);
  EXPECT_EQ(unthrottled, kSlots) << "with nothing that ends its tree, a throttled round still fills the banks";
}

TEST(Bench, ScatterPointIsSane) {
  const ScatterPoint p = measure_scatter(runtime(), 4096, 16, 1, 2);
  EXPECT_TRUE(p.verified);
  EXPECT_EQ(p.moved, 4096u);
  EXPECT_GT(p.host_seconds, 0.0);
  EXPECT_GT(p.kernel_seconds, 0.0);
  EXPECT_GT(p.speedup(), 0.0);
  EXPECT_GT(p.gbytes_per_s(), 0.0);
  EXPECT_GT(p.copy_kernel_gbytes_per_s(), 0.0);
  EXPECT_GT(p.copy_buffer_gbytes_per_s(), 0.0);
  EXPECT_GT(p.six_vectors_gbytes_per_s(), 0.0);  // the paper's six-vector scatter, the reference point
  EXPECT_GT(p.one_record_gbytes_per_s(), 0.0);
}

TEST(Bench, FlagErrorsAreInputErrors) {
  OneProcess solo;  // one process
  EXPECT_THROW(run_bench({}, solo), InputError);
  EXPECT_THROW(run_bench({"scene.json", "-o", "x.png"}, solo), InputError);
  EXPECT_THROW(run_bench({"scene.json", "--stats", "x.json"}, solo), InputError);
  EXPECT_THROW(run_bench({"scene.json", "--repeats", "0"}, solo), InputError);
  EXPECT_THROW(run_bench({"scene.json", "--warmup", "x"}, solo), InputError);
  EXPECT_THROW(run_bench({"scene.json", "--json", "out.txt"}, solo), InputError);
  EXPECT_THROW(run_bench({"scene.json", "--json"}, solo), InputError);
  EXPECT_THROW(run_bench({"scene.json", "--quick=1"}, solo), InputError);
  EXPECT_THROW(run_bench({"scene.json", "--repeats", "2", "--repeats", "3"}, solo), InputError);
  EXPECT_THROW(run_bench({"scene.json", "--pes", "0"}, solo), InputError);
  EXPECT_THROW(run_bench({"scene.json", "--size", "10"}, solo), InputError);
  EXPECT_THROW(run_bench({"a.json", "b.json"}, solo), InputError);
  EXPECT_THROW(run_bench({"scene.json", "--frobnicate"}, solo), InputError);
}

TEST(Bench, CommandLineErrorIsOneLineExitTwo) {
  const test::RunResult r = test::run_opsila({"bench", "scene.json", "--repeats", "-1"});
  EXPECT_EQ(r.exit_code, 2);
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find("opsila: error: --repeats"), std::string::npos) << r.err;
}

// The scatter curve stops at the longest vector the device can hold and
// says why, instead of failing the whole bench (a 2^24 point needs a 2.2 GB
// buffer, more than PoCL allows on a 24 GB machine).
TEST(Bench, TheScatterCurveStopsWhereTheDeviceIsFull) {
  test::TempDir dir;
  const std::string json_path = dir.file("bench.json");
  const test::RunResult r = test::run_program(
      OPSILA_BINARY,
      {"bench", std::string(OPSILA_SOURCE_DIR) + "/scenes/whitted.json", "--size", "16x12", "--depth", "2", "--pes",
       "4", "--balance", "facets", "--repeats", "1", "--scatter-max", "22", "--json", json_path},
      {{"OPSILA_DEVICE_MEMORY_LIMIT", std::to_string(200u << 20)}});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("the curve stops at 2^19: 2^20 needs a buffer of"), std::string::npos) << r.out;
  const nlohmann::json j = nlohmann::json::parse(test::read_file(json_path));
  EXPECT_EQ(j["scatter"].back()["length"], 1 << 19);
  EXPECT_TRUE(j["scatter_limit"].is_string());
  EXPECT_EQ(j["scatter_by_pes"].front()["length"], 1 << 19);
}

// And within --host-memory: the default curve took 5.6 GB of a CPU
// device's host memory whatever the flag said.
TEST(Bench, TheScatterCurveStopsWithinTheHostMemoryGiven) {
  test::TempDir dir;
  const std::string json_path = dir.file("bench.json");
  const test::RunResult r = test::run_opsila(
      {"bench", std::string(OPSILA_SOURCE_DIR) + "/scenes/whitted.json", "--size", "16x12", "--depth", "2", "--pes",
       "4", "--balance", "facets", "--repeats", "1", "--scatter-max", "20", "--host-memory", "300M", "--json", json_path});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("the curve stops at 2^19: 2^20 needs a buffer of"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--host-memory allows 300.0 MiB"), std::string::npos) << r.out;
  const nlohmann::json j = nlohmann::json::parse(test::read_file(json_path));
  EXPECT_EQ(j["scatter"].back()["length"], 1 << 19);
}

// The renders on the same rays run in rounds, one frame of each a round, so
// every one of them has a timed frame in every timed round (Embree too,
// where it used to run the host references' count); the host references
// run after the rounds, at most 3 times.
TEST(Bench, RendersRunInRoundsOneFrameOfEachARound) {
  test::TempDir dir;
  const std::string json_path = dir.file("bench.json");
  const test::RunResult r = test::run_opsila({"bench", std::string(OPSILA_SOURCE_DIR) + "/scenes/whitted.json",
                                              "--size", "32x24", "--depth", "2", "--pes", "4", "--quick",
                                              "--scatter-max", "4", "--repeats", "4", "--json", json_path});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("timing: median of 4 rounds after 1 warm-up"), std::string::npos) << r.out;
  const nlohmann::json j = nlohmann::json::parse(test::read_file(json_path));
  EXPECT_EQ(j["render"]["seconds_all"].size(), 4u);
  EXPECT_EQ(j["baselines"]["replicated_megakernel"]["seconds_all"].size(), 4u);
  EXPECT_EQ(j["traversal_alone"]["seconds_all"].size(), 4u);
  if (embree_available()) EXPECT_EQ(j["baselines"]["embree"]["seconds_all"].size(), 4u);
  EXPECT_EQ(j["baselines"]["sequential_host"]["seconds_all"].size(), 3u);
}

TEST(Bench, QuickRunWritesEveryJsonKey) {
  test::TempDir dir;
  const std::string json_path = dir.file("bench.json"), csv = dir.file("csv");
  const test::RunResult r = test::run_opsila({"bench", std::string(OPSILA_SOURCE_DIR) + "/scenes/whitted.json",
                                              "--size", "48x36", "--depth", "3", "--pes", "8", "--quick",
                                              "--scatter-max", "12", "--repeats", "1", "--json", json_path, "--csv",
                                              csv});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("scatter"), std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(test::read_file(json_path));

  ASSERT_TRUE(j.contains("device"));
  EXPECT_FALSE(j["device"].get<std::string>().empty());
  EXPECT_EQ(j["pes"], 8);
  EXPECT_EQ(j["depth"], 3);
  EXPECT_EQ(j["image"]["width"], 48);
  EXPECT_GT(j["scene"]["facets"].get<int>(), 0);
  EXPECT_GT(j["scene"]["clusters"].get<int>(), 0);
  // The bench balances by measured work unless told otherwise.
  EXPECT_EQ(j["balance"], "measured");
  EXPECT_GE(j["pilot_frames"].get<int>(), 1);
  EXPECT_NE(r.out.find("balance measured: the partition of the best of"), std::string::npos) << r.out;

  const nlohmann::json& rj = j["render"];
  EXPECT_EQ(rj["rays"].get<std::uint64_t>(), 48u * 36u + rj["rays_by_kind"]["secondary"].get<std::uint64_t>() +
                                                  rj["rays_by_kind"]["shadow"].get<std::uint64_t>());
  EXPECT_GT(rj["seconds"].get<double>(), 0.0);
  EXPECT_GT(rj["mrays_per_s"].get<double>(), 0.0);
  ASSERT_TRUE(rj["phases"].is_array());
  EXPECT_FALSE(rj["phases"].empty());
  bool saw_spmd = false, saw_scatter = false;
  for (const auto& p : rj["phases"]) {
    EXPECT_GE(p["seconds"].get<double>(), 0.0);
    saw_spmd |= p["name"] == "spmd_phase";
    saw_scatter |= p["name"] == "scatter_move";
  }
  EXPECT_TRUE(saw_spmd && saw_scatter);
  EXPECT_EQ(rj["phase_switches"].get<int>(), 2 * rj["rounds"].get<int>());
  ASSERT_EQ(rj["pe"].size(), 8u);
  const double occ = rj["occupancy"].get<double>();
  EXPECT_GT(occ, 0.0);
  EXPECT_LE(occ, 1.0);
  for (const auto& level : rj["levels"])
    if (!level["occupancy"].is_null()) {
      EXPECT_GT(level["occupancy"].get<double>(), 0.0);
      EXPECT_LE(level["occupancy"].get<double>(), 1.0);
    }
  EXPECT_EQ(rj["traffic"].size(), 3u);
  EXPECT_GE(rj["exchange_share"].get<double>(), 0.0);
  EXPECT_TRUE(rj["deterministic"].get<bool>());
  // The work is counted (in a frame of its own: the timed frames count
  // only rays, as a plain render does) and reported beside the times.
  EXPECT_GT(rj["work"]["triangle_tests"].get<std::uint64_t>(), 0u);
  EXPECT_GT(rj["work"]["box_tests"].get<std::uint64_t>(), 0u);
  // Destination choice is counted: the default routes on cluster boxes.
  EXPECT_EQ(j["routing"], "boxes");
  EXPECT_GT(rj["work"]["route_tests"].get<std::uint64_t>(), 0u);
  EXPECT_EQ(rj["work"]["routing_tests"].get<std::uint64_t>(),
            rj["work"]["route_tests"].get<std::uint64_t>() + rj["work"]["sphere_tests"].get<std::uint64_t>());

  ASSERT_TRUE(j["scatter"].is_array());
  ASSERT_FALSE(j["scatter"].empty());
  for (const auto& p : j["scatter"]) {
    EXPECT_GT(p["length"].get<std::size_t>(), 0u);
    EXPECT_GT(p["speedup"].get<double>(), 0.0);
    EXPECT_GT(p["gbytes_per_s"].get<double>(), 0.0);
    EXPECT_GT(p["six_vectors_gbytes_per_s"].get<double>(), 0.0);
    EXPECT_GT(p["one_record_gbytes_per_s"].get<double>(), 0.0);
    EXPECT_TRUE(p["verified"].get<bool>());
  }
  for (const char* target : {"scatter_2p20_vs_copy", "exchange_plus_overhead", "occupancy", "rounds",
                             "opsila_vs_megakernel", "opsila_vs_embree"})
    EXPECT_TRUE(j["targets"].contains(target)) << target;
  EXPECT_TRUE(j["targets"]["rounds"]["met"].is_boolean());
  EXPECT_EQ(j["scatter"].front()["length"], 16);
  EXPECT_GT(j["copy_gbytes_per_s"].get<double>(), 0.0);
  EXPECT_GT(j["memory"]["bank_bytes_max"].get<std::uint64_t>(), 0u);
  EXPECT_GT(j["memory"]["replicated_bytes"].get<std::uint64_t>(), j["memory"]["bank_bytes_max"].get<std::uint64_t>());
  // What a triangle costs: the device's planned bytes (banks, image, descriptors) and the peak host set.
  const nlohmann::json& cost = j["triangle_cost"];
  EXPECT_EQ(cost["triangles"], j["scene"]["triangles"]);
  EXPECT_GT(cost["device_bytes"].get<std::uint64_t>(), j["memory"]["bank_bytes_max"].get<std::uint64_t>());
  EXPECT_NEAR(cost["device_bytes_per_triangle"].get<double>(),
              cost["device_bytes"].get<double>() / cost["triangles"].get<double>(), 1e-6);
  EXPECT_GT(cost["host_peak_bytes_per_triangle"].get<double>(), 0.0);

  const nlohmann::json& b = j["baselines"];
  EXPECT_GT(b["replicated_megakernel"]["mrays_per_s"].get<double>(), 0.0);
  EXPECT_TRUE(b["replicated_megakernel"]["rays_match_opsila"].get<bool>());
  EXPECT_GT(b["sequential_host"]["mrays_per_s"].get<double>(), 0.0);
  EXPECT_EQ(b["sequential_host"]["threads"], 1);
  if (embree_available()) {
    EXPECT_GT(b["embree"]["mrays_per_s"].get<double>(), 0.0);
  } else {
    EXPECT_FALSE(b.contains("embree"));
  }

  for (const char* name : {"scatter.csv", "phases.csv", "levels.csv", "occupancy.csv", "traffic.csv", "baselines.csv"})
    EXPECT_TRUE(test::file_exists(csv + "/" + name)) << name;

  // The traversal alone: the megakernel's rays, and every render per ray beside it.
  const nlohmann::json& t = j["traversal_alone"];
  ASSERT_TRUE(t.is_object()) << t.dump();
  const nlohmann::json& mk = b["replicated_megakernel"];
  EXPECT_EQ(t["rays"], mk["rays"]);
  EXPECT_TRUE(t["rays_match_megakernel"].get<bool>());
  EXPECT_EQ(t["nearest_rays"].get<std::uint64_t>(), mk["rays_by_kind"]["primary"].get<std::uint64_t>() +
                                                        mk["rays_by_kind"]["secondary"].get<std::uint64_t>());
  EXPECT_EQ(t["any_rays"], mk["rays_by_kind"]["shadow"]);
  EXPECT_GT(t["seconds"].get<double>(), 0.0);
  EXPECT_GT(t["mrays_per_s"].get<double>(), 0.0);
  for (const char* key : {"megakernel_kernels_over_traversal", "megakernel_over_traversal", "opsila_over_traversal"})
    EXPECT_GT(t[key].get<double>(), 0.0) << key;
  EXPECT_NE(r.out.find("traversal alone (the megakernel's BVH and rays"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("OPSILA, frame"), std::string::npos) << r.out;
  EXPECT_NE(test::read_file(csv + "/baselines.csv").find("\ntraversal_alone,"), std::string::npos);

  // Launches per frame: every kernel's launches.
  int launches = 0;
  for (const auto& [name, k] : rj["time_by_kernel"].items()) launches += k["launches"].get<int>();
  EXPECT_EQ(rj["launches_per_frame"].get<int>(), launches);
  // Cycles by stage where the device counts them, else why not.
  if (j["stages_skipped"].is_string()) {
    EXPECT_FALSE(j["stages_skipped"].get<std::string>().empty());
    EXPECT_TRUE(j["stages"]["spmd_phase"].is_null());
  } else {
    for (const char* kernel : {"spmd_phase", "megakernel"}) {
      const nlohmann::json& st = j["stages"][kernel]["stages"];
      ASSERT_TRUE(st.is_object()) << kernel;
      EXPECT_GT(j["stages"][kernel]["clocked_over_timed"].get<double>(), 0.0) << kernel;
      EXPECT_TRUE(st.contains("bank_walk")) << kernel;
      double share = 0;
      for (const auto& [name, v] : st.items()) share += v["share"].get<double>();
      EXPECT_NEAR(share, 1.0, 1e-9) << kernel;
    }
    EXPECT_NE(r.out.find("cycles by stage"), std::string::npos) << r.out;
  }
}


// ------------------------------------------------------------ --compare

// A bench result by hand: only the keys the comparison reads.
nlohmann::json saved_result(double render_seconds, double mrays, int pes) {
  return {{"device", "dev"},
          {"pes", pes},
          {"depth", 3},
          {"scene", {{"path", "s.json"}}},
          {"image", {{"width", 8}, {"height", 6}}},
          {"render", {{"seconds", render_seconds}, {"mrays_per_s", mrays}}},
          {"scatter", nlohmann::json::array({{{"length", 1024}, {"gbytes_per_s", 2.0}}})}};
}

TEST(BenchCompare, RatiosOfTheFiguresBothRunsHave) {
  nlohmann::json now = saved_result(1.0, 3.0, 8), saved = saved_result(4.0, 1.5, 8);
  saved["scatter"][0]["gbytes_per_s"] = 8.0;
  saved["baselines"] = {{"embree", {{"seconds", 2.0}}}};  // this run has none: left out
  const std::string text = compare_text(now, saved, "old.json");
  EXPECT_NE(text.find("compared with old.json"), std::string::npos) << text;
  EXPECT_NE(text.find("render seconds"), std::string::npos) << text;
  EXPECT_NE(text.find("0.25x"), std::string::npos) << text;  // 1 s now, 4 s saved
  EXPECT_NE(text.find("2x"), std::string::npos) << text;     // 3 vs 1.5 Mrays/s
  EXPECT_NE(text.find("scatter 2^10 GB/s"), std::string::npos) << text;
  EXPECT_EQ(text.find("embree"), std::string::npos) << text;
  EXPECT_EQ(text.find("note:"), std::string::npos) << text;
  EXPECT_NE(compare_text(saved_result(1, 1, 4), saved, "old.json").find("note: the runs differ"), std::string::npos);
  // A saved string's control bytes are shown, not sent (a NUL cut the report).
  saved["device"] = std::string("x\0y\x1b[2J", 8);
  const std::string odd = compare_text(now, saved, "old.json");
  EXPECT_EQ(odd.find('\0'), std::string::npos);
  EXPECT_NE(odd.find("saved run was on x\\x00y\\x1b[2J"), std::string::npos) << odd;
}

TEST(BenchCompare, ASavedRunMustBeABenchResult) {
  test::TempDir dir;
  EXPECT_THROW(read_saved_bench(dir.file("none.json")), InputError);
  EXPECT_THROW(read_saved_bench(dir.write("bad.json", "{ not json")), InputError);
  EXPECT_THROW(read_saved_bench(dir.write("other.json", "{\"a\": 1}")), InputError);
  EXPECT_NO_THROW(read_saved_bench(dir.write("ok.json", saved_result(1, 1, 1).dump())));
  // Its shape is checked before the parse (40 MiB of '[' took 3.1 GB there).
  test::expect_error([&] { read_saved_bench(dir.write("deep.json", std::string(1 << 23, '['))); },
                     {"deep.json:1: nesting deeper than 16 levels"});
  // A key given twice (an edited file): the parse kept the last; refused.
  std::string twice = saved_result(1, 1, 1).dump();
  twice.insert(1, "\"depth\": 99, ");
  test::expect_error([&] { read_saved_bench(dir.write("twice.json", twice)); },
                     {"twice.json:1: depth: key given twice (a saved bench result holds each key once)"});
  // A figure that is no number >= 0 (an edited file): refused, named; it
  // had printed a negative ratio, or dropped its row unsaid.
  for (const nlohmann::json& bad : {nlohmann::json(-1.0), nlohmann::json("fast"), nlohmann::json(nullptr)}) {
    nlohmann::json edited = saved_result(1, 1, 1);
    edited["render"]["seconds"] = bad;
    test::expect_error([&] { read_saved_bench(dir.write("edited.json", edited.dump())); },
                       {"edited.json: render seconds ('seconds'): expected a number >= 0, not " + bad.dump()});
  }
  nlohmann::json scatter = saved_result(1, 1, 1);
  scatter["scatter"][0]["gbytes_per_s"] = -2;
  test::expect_error([&] { read_saved_bench(dir.write("scatter.json", scatter.dump())); },
                     {"scatter 2^10 GB/s ('gbytes_per_s'): expected a number >= 0, not -2"});
  const test::RunResult r = test::run_opsila({"bench", "scene.json", "--compare", dir.file("none.json")});
  EXPECT_EQ(r.exit_code, 2);
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find("opsila: error: --compare"), std::string::npos) << r.err;
  EXPECT_EQ(test::run_opsila({"bench", "scene.json", "--compare", "old.txt"}).exit_code, 2);
}

// A saved run whose settings have the wrong type is refused when it is
// read, naming the key, before the bench writes (or overwrites) anything.
TEST(BenchCompare, ASavedRunWithMistypedSettingsIsRefusedFirst) {
  test::TempDir dir;
  const std::vector<std::pair<std::string, nlohmann::json>> bad = {
      {"device", 5},          {"depth", "5"},          {"pes", 2.5},         {"context", 1},  {"depth", -1},
      {"pes", std::uint64_t(-1)},
      {"scene", {{"path", 3}}}, {"image", {{"width", "8"}}}, {"context", {{"date", 7}}}};
  for (const auto& [key, value] : bad) {
    nlohmann::json j = saved_result(1, 1, 1);
    j[key] = value;
    const std::string path = dir.write("typed.json", j.dump());
    try {
      read_saved_bench(path);
      ADD_FAILURE() << key << " = " << value.dump() << " was read";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path + ": " + key), std::string::npos) << e.what();
    }
  }
  nlohmann::json j = saved_result(1, 1, 1);
  j["image"]["height"] = "6";
  const std::string saved = dir.write("typed.json", j.dump());
  const std::string out = dir.write("out.json", "precious");
  const test::RunResult r = test::run_opsila({"bench", std::string(OPSILA_SOURCE_DIR) + "/scenes/whitted.json",
                                              "--quick", "-q", "--json", out, "--compare", saved});
  EXPECT_EQ(r.exit_code, 2);
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find("image.height: expected a whole number"), std::string::npos) << r.err;
  EXPECT_EQ(test::read_file(out), "precious");
}

// Two quick runs: the second prints each figure beside the first's, and both
// carry the context block and min/median/max of every timed figure.
TEST(BenchCompare, TwoSavedRuns) {
  test::TempDir dir;
  const std::string first = dir.file("first.json"), second = dir.file("second.json");
  const std::vector<std::string> quick = {"bench",  std::string(OPSILA_SOURCE_DIR) + "/scenes/whitted.json",
                                          "--size", "32x24", "--depth", "2", "--pes", "4", "--quick",
                                          "--scatter-max", "8", "--repeats", "2", "-q"};
  std::vector<std::string> args = quick;
  args.insert(args.end(), {"--json", first});
  ASSERT_EQ(test::run_opsila(args).exit_code, 0);
  args = quick;
  args.insert(args.end(), {"--json", second, "--compare", first});
  const test::RunResult r = test::run_opsila(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;

  const nlohmann::json a = nlohmann::json::parse(test::read_file(first));
  const nlohmann::json b = nlohmann::json::parse(test::read_file(second));
  EXPECT_NE(r.out.find("compared with " + first), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("note:"), std::string::npos) << r.out;  // same settings, same device
  for (const BenchFigure& f : bench_figures(b)) EXPECT_NE(r.out.find(f.name), std::string::npos) << f.name;
  EXPECT_GE(bench_figures(b).size(), 10u);
  // The render's line, as this run's and the saved values and their ratio.
  const auto g4 = [](double v) {
    char t[32];
    std::snprintf(t, sizeof t, "%.4g", v);
    return std::string(t);
  };
  const double now = b["render"]["seconds"], then = a["render"]["seconds"];
  char expected[160];
  std::snprintf(expected, sizeof expected, "  %-40s %12s %12s %8s", "render seconds", g4(now).c_str(),
                g4(then).c_str(), (g4(now / then) + "x").c_str());
  EXPECT_NE(r.out.find(expected), std::string::npos) << expected << "\n" << r.out;

  for (const nlohmann::json* j : {&a, &b}) {
    const nlohmann::json& c = (*j)["context"];
    for (const char* key : {"date", "host_name", "num_cpus", "load_avg", "library_build_type", "device",
                            "driver_version"})
      EXPECT_TRUE(c.contains(key)) << key;
    EXPECT_GT(c["num_cpus"].get<int>(), 0);
    auto ordered = [](const nlohmann::json& s) {
      return s["min"].get<double>() <= s["median"].get<double>() && s["median"].get<double>() <= s["max"].get<double>();
    };
    EXPECT_TRUE(ordered((*j)["render"]["seconds_spread"]));
    EXPECT_EQ((*j)["render"]["seconds_spread"]["median"], (*j)["render"]["seconds"]);
    for (const auto& [name, base] : (*j)["baselines"].items()) EXPECT_TRUE(ordered(base["seconds_spread"])) << name;
    for (const auto& p : (*j)["scatter"]) {
      EXPECT_TRUE(ordered(p["kernel_seconds_spread"]));
      EXPECT_EQ(p["kernel_seconds_spread"]["median"], p["kernel_seconds"]);
      EXPECT_TRUE(ordered(p["host_seconds_spread"]));
      EXPECT_TRUE(ordered(p["copy_kernel_seconds_spread"]));
    }
  }
}

}  // namespace
}  // namespace opsila
