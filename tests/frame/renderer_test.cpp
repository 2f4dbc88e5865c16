// The OpenCL renderer against the sequential reference (docs/CONTRACT.md in plain
// C++), across PE counts, bank capacities and runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <memory>

#include "formats/json/scene_file.h"
#include "opsila_shared.h"
#include "reference/reference.h"
#include "frame/renderer.h"
#include "frame/frame.h"
#include "device/memory_plan.h"
#include "partition/partition.h"
#include "dist/pilot.h"
#include "prepare/prepare_banks.h"
#include "frame/stats.h"
#include "test_device.h"
#include "test_scenes.h"
#include "test_util.h"

namespace opsila {
namespace {

ClRuntime& runtime() { return test::shared_runtime(); }

RenderResult render_with(const Scene& s, int pes, int capacity = 0) {
  RenderSettings rs;
  rs.num_pes = pes;
  rs.bank_capacity = capacity;
  return render(s, rs, runtime());
}

using test::item_agreement;

void expect_balanced(const RenderStats& st) {
  EXPECT_GT(st.descriptors_spawned, 0u);
  EXPECT_EQ(st.descriptors_spawned, st.descriptors_finished) << "a descriptor was lost or counted twice";
}

TEST(Renderer, MatchesReferenceOnMirrorsGlassAndShadows) {
  Scene s = test::mirror_glass_scene(160);
  RenderResult r = render_with(s, 16);
  ImageResult ref = render_reference(s);
  EXPECT_GE(test::clamped_psnr(r.rgb, ref.rgb), 40.0);
  EXPECT_LE(test::fraction_off(r.rgb, ref.rgb, 2), 0.005);
  EXPECT_GE(item_agreement(r.item_buffer, ref.item_buffer), 0.999);
  expect_balanced(r.stats);
  EXPECT_GT(r.rays.secondary, 0u);
  EXPECT_GT(r.rays.shadow, 0u);
}

// The item buffer lists no cluster whose box lies wholly behind the eye (no
// primary ray can meet it), and the image stays the reference's: turned
// away from the scene, every pixel is background and no pixel tests a box.
// Only hits become primary descriptors (the hit list, kernels/primary.cl):
// with every pixel a miss, no descriptor is built and no round runs, with
// one sample or four.
TEST(Renderer, ClustersBehindTheEyeAreNeverListed) {
  Scene s = test::mirror_glass_scene(48);
  auto listed = [](const Scene& sc) {
    const BankedScene bs = partition_scene(sc, 4);
    int n = 0;
    for (const cl_int4& r : cluster_rects(sc, bs.clusters)) n += r.s[0] <= r.s[2] && r.s[1] <= r.s[3];
    return std::make_pair(n, int(bs.clusters.size()));
  };
  const auto facing = listed(s);
  EXPECT_EQ(facing.first, facing.second);
  for (int i = 0; i < 3; ++i) s.camera.look_at[i] = 2 * s.camera.eye[i] - s.camera.look_at[i];
  EXPECT_EQ(listed(s).first, 0);
  const ImageResult ref = render_reference(s);
  for (int pes : {1, 16}) {
    const RenderResult r = render_with(s, pes);
    EXPECT_GE(test::clamped_psnr(r.rgb, ref.rgb), 40.0) << pes;
    for (std::size_t i = 3; i < r.rgb.size(); ++i) ASSERT_EQ(r.rgb[i], r.rgb[i % 3]) << pes;  // all background
    EXPECT_EQ(r.item_buffer, ref.item_buffer) << pes;
    EXPECT_EQ(r.rays.primary_hits, 0u) << pes;
    EXPECT_EQ(r.stats.rounds, 0) << pes;
    for (const LaunchRecord& l : r.stats.launches)
      EXPECT_TRUE(l.name != "build_primary" && l.name.compare(0, 8, "scatter_") != 0) << l.name << " " << pes;
  }
  s.spp = 4;
  const RenderResult four = render_with(s, 16);
  EXPECT_EQ(four.rays.primary_hits, 0u);
  EXPECT_EQ(four.stats.rounds, 0);
  int passes = 0;
  for (const LaunchRecord& l : four.stats.launches) passes += l.name == "count_hits";
  EXPECT_EQ(passes, 4) << "one hit list per sample pass";
  EXPECT_EQ(four.rgb, render_with([&] { Scene one = s; one.spp = 1; return one; }(), 16).rgb);
}

// Seen from far, the scene covers the middle of the screen: the union of
// the projected cluster boxes, which lets the item buffer skip the tiles
// outside it, holds every box and leaves the screen's edges out, and the
// image and item buffer stay the reference's.
TEST(Renderer, TilesOutsideEveryClusterBoxListNothing) {
  Scene s = test::mirror_glass_scene(64);
  for (int i = 0; i < 3; ++i) s.camera.eye[i] = s.camera.look_at[i] + 4 * (s.camera.eye[i] - s.camera.look_at[i]);
  const BankedScene bs = partition_scene(s, 4);
  const std::vector<cl_int4> rects = cluster_rects(s, bs.clusters);
  const cl_int4 u = rects_union(rects);
  for (const cl_int4& r : rects) {
    EXPECT_LE(u.s[0], r.s[0]);
    EXPECT_LE(u.s[1], r.s[1]);
    EXPECT_GE(u.s[2], r.s[2]);
    EXPECT_GE(u.s[3], r.s[3]);
  }
  EXPECT_GT(u.s[0], 8);  // at least one tile of each edge lies outside
  EXPECT_GT(u.s[1], 8);
  EXPECT_LT(u.s[2], s.width - 9);
  EXPECT_LT(u.s[3], s.height - 9);
  const cl_int4 none = rects_union({});
  EXPECT_TRUE(none.s[0] > none.s[2] && none.s[1] > none.s[3]);  // no box: no tile lists anything
  const ImageResult ref = render_reference(s);
  for (int pes : {1, 16}) {
    const RenderResult r = render_with(s, pes);
    EXPECT_GE(test::clamped_psnr(r.rgb, ref.rgb), 40.0) << pes;
    EXPECT_GE(item_agreement(r.item_buffer, ref.item_buffer), 0.999) << pes;
    EXPECT_GT(r.rays.primary_hits, 0u) << pes;
    EXPECT_LT(r.rays.primary_hits, std::uint64_t(s.width) * s.height / 2) << pes;
  }
}

TEST(Renderer, DepthOneIsLocalShadingOnly) {
  Scene s = test::mirror_glass_scene(64, 1);
  RenderResult r = render_with(s, 4);
  ImageResult ref = render_reference(s);
  EXPECT_GE(test::clamped_psnr(r.rgb, ref.rgb), 40.0);
  EXPECT_EQ(r.rays.secondary, 0u);
  expect_balanced(r.stats);
}

// Two facing glass slabs: every hit spawns a reflected and a refracted ray,
// so a pixel's ray tree doubles with each level (CONTRACT's depth) until its
// rays leave the slabs' sides.
Scene facing_slabs(int depth) {
  const std::string text = R"({"image": {"size": [64, 48]}, "depth": )" + std::to_string(depth) + R"(,
    "camera": {"eye": [0, 0, 0.5], "look_at": [0, 0, -1]},
    "materials": {"glass": {"kr": 0.9, "kt": 0.9, "Ni": 1.5}},
    "objects": [{"type": "box", "min": [-50, -50, -1.1], "max": [50, 50, -1], "material": "glass"},
                {"type": "box", "min": [-50, -50, 1], "max": [50, 50, 1.1], "material": "glass"}]})";
  return load_scene_from_string(text, "facing slabs", "");
}

// The exchange takes the newest records first (kernels/scatter.cl), so the
// ray trees are worked depth first and what waits stays within the planned
// pool once a level. Taking the oldest first held about 241,000 records on
// this scene (a level of every tree at once), above that bound (174,336);
// depth first holds about 30,000.
TEST(Renderer, RayTreesAreWorkedDepthFirst) {
  constexpr int kDepth = 12, kPes = 16;
  const RenderResult r = render_with(facing_slabs(kDepth), kPes);
  expect_balanced(r.stats);
  const FlightPlan plan(kPes, r.stats.bank_capacity, std::size_t(r.stats.work_group_size), OPSILA_SPAWN_SLOTS(0));
  EXPECT_GT(r.rays.secondary, 1000000u) << "the trees should be deep and wide";
  EXPECT_LE(r.stats.waiting_peak, plan.pool * kDepth);
  EXPECT_GT(r.stats.waiting_peak, 0u);
  EXPECT_EQ(r.stats.throttled_rounds, 0) << "below the limit the exchange is not throttled";
}

// Beyond the waiting limit the exchange takes only the rays that end their
// tree: the rounds change, never the bytes of the image, and no ray is lost.
TEST(Renderer, AThrottledExchangeGivesTheSameImage) {
  for (const Scene& s : {facing_slabs(8), test::mirror_glass_scene(48)}) {
    const RenderResult free_run = render_with(s, 16);
    ::setenv("OPSILA_WAITING_LIMIT", "200", 1);
    const RenderResult held = render_with(s, 16);
    ::unsetenv("OPSILA_WAITING_LIMIT");
    EXPECT_EQ(free_run.stats.throttled_rounds, 0);
    EXPECT_GT(held.stats.throttled_rounds, 0);
    ASSERT_EQ(held.rgb.size(), free_run.rgb.size());
    EXPECT_EQ(0, std::memcmp(held.rgb.data(), free_run.rgb.data(), held.rgb.size() * sizeof(float)));
    EXPECT_EQ(held.item_buffer, free_run.item_buffer);
    expect_balanced(held.stats);
    EXPECT_EQ(held.stats.descriptors_spawned, free_run.stats.descriptors_spawned);
  }
}

// The image is the same bit for bit on every PE count: the same facet wins
// every ray whichever bank holds it.
TEST(Renderer, PartitionInvariance) {
  Scene s = test::mirror_glass_scene(96);
  RenderResult base = render_with(s, 1);
  for (int pes : {4, 16, 64, 256}) {
    RenderResult r = render_with(s, pes);
    ASSERT_EQ(r.rgb.size(), base.rgb.size());
    EXPECT_EQ(0, std::memcmp(r.rgb.data(), base.rgb.data(), r.rgb.size() * sizeof(float))) << pes << " PEs";
    EXPECT_EQ(r.item_buffer, base.item_buffer) << pes << " PEs";
    expect_balanced(r.stats);
    EXPECT_EQ(r.stats.descriptors_spawned, base.stats.descriptors_spawned) << pes << " PEs";
  }
}

// A glass block standing on a floor: a ray leaving the block's face near the
// floor meets the floor and the block's coplanar bottom a hair's breadth
// away. The facet test rounds t at the scale of the coordinates, not of t,
// so the floor's t fell below its own box's entry there and the bank BVH
// culled it when the block's bottom was found first (one bank), but not
// when the floor sat in a bank of its own (64 PEs): 4 pixels of Cornell at
// 512x512 (2 at 256x256, depth 5) differed. The culling's absolute slack
// (FrameParams.box_slack) keeps such boxes open.
TEST(Renderer, CoplanarFacetsNearTheOriginAreTheSameOnEveryPeCount) {
  Scene s = load_scene(std::string(OPSILA_SOURCE_DIR) + "/scenes/cornell.json");
  s.width = s.height = 256;
  const RenderResult base = render_with(s, 1);
  for (int pes : {16, 64}) {
    const RenderResult r = render_with(s, pes);
    ASSERT_EQ(r.rgb.size(), base.rgb.size());
    EXPECT_EQ(0, std::memcmp(r.rgb.data(), base.rgb.data(), r.rgb.size() * sizeof(float))) << pes << " PEs";
    EXPECT_EQ(r.stats.descriptors_spawned, base.stats.descriptors_spawned) << pes << " PEs";
  }
}

// Cluster boxes and the paper's spheres choose destinations by one rule, so
// they give the same image bit for bit, with fewer descriptors for boxes.
TEST(Renderer, RoutingOnBoxesOrSpheresGivesTheSameImage) {
  Scene s = test::mirror_glass_scene(64);
  for (int pes : {1, 4, 16, 64}) {
    RenderSettings rs;
    rs.num_pes = pes;
    rs.routing = OPSILA_ROUTING_SPHERES;
    RenderResult spheres = render(s, rs, runtime());
    rs.routing = OPSILA_ROUTING_BOXES;
    RenderResult boxes = render(s, rs, runtime());
    ASSERT_EQ(spheres.rgb.size(), boxes.rgb.size());
    EXPECT_EQ(0, std::memcmp(spheres.rgb.data(), boxes.rgb.data(), boxes.rgb.size() * sizeof(float))) << pes;
    EXPECT_EQ(spheres.item_buffer, boxes.item_buffer) << pes << " PEs";
    expect_balanced(boxes.stats);
    EXPECT_EQ(spheres.stats.descriptors_spawned, boxes.stats.descriptors_spawned) << pes << " PEs";
  }
}

double occupancy(const RenderStats& st) { return test_occupancy(st); }

// A rebalanced partition (`other`) against equal banks: the same image and
// item buffer bit for bit, no ray lost, every facet still in exactly one bank.
void expect_same_image_other_banks(const RenderResult& facets, const RenderResult& other, int pes) {
  ASSERT_EQ(facets.rgb.size(), other.rgb.size());
  EXPECT_EQ(0, std::memcmp(facets.rgb.data(), other.rgb.data(), other.rgb.size() * sizeof(float))) << pes << " PEs";
  EXPECT_EQ(facets.item_buffer, other.item_buffer) << pes << " PEs";
  expect_balanced(other.stats);
  std::uint64_t facet_bytes = 0, other_bytes = 0;
  for (std::uint64_t b : facets.stats.bank_bytes) facet_bytes += b;
  for (std::uint64_t b : other.stats.bank_bytes) other_bytes += b;
  EXPECT_NEAR(double(other_bytes), double(facet_bytes), 0.05 * double(facet_bytes)) << "facets duplicated or lost";
}

// A partition that shares the frame's sampled rays (--balance work) moves
// facets between banks, never a pixel; on a scene whose work gathers under
// the camera it spreads the tests more evenly than equal banks do.
TEST(Renderer, BalancingByWorkGivesTheSameImageAndEvenerPes) {
  Scene s = load_scene(std::string(OPSILA_SOURCE_DIR) + "/scenes/hundreds.json");
  s.width = 160;
  s.height = 120;
  const RaySample sample = ReferenceTracer(s).sample_rays(4000);
  EXPECT_GT(sample.rays.size(), 4000u * 3 / 4) << "every sampled primary ray is recorded, and its tree";
  for (int pes : {4, 16}) {
    RenderSettings rs;
    rs.num_pes = pes;
    const RenderResult facets = render(s, rs, runtime());
    rs.balance = Balance::work;
    rs.ray_sample = &sample;
    const RenderResult work = render(s, rs, runtime());
    expect_same_image_other_banks(facets, work, pes);
    EXPECT_EQ(work.stats.balance, Balance::work);
    EXPECT_GT(occupancy(work.stats), occupancy(facets.stats) + 0.05) << pes << " PEs";
  }
}

// --balance measured: pilot frames count each cluster's tests on the
// device, and the partition shares them level by level. Facets move between
// banks, never a pixel; the PEs are far more even than with equal banks, and
// the partition is the same every time (the counts are deterministic).
TEST(Renderer, BalancingByMeasuredWorkGivesTheSameImageAndEvenerPes) {
  Scene s = load_scene(std::string(OPSILA_SOURCE_DIR) + "/scenes/hundreds.json");
  s.width = 160;
  s.height = 120;
  for (int pes : {4, 16}) {
    RenderSettings rs;
    rs.num_pes = pes;
    const RenderResult facets = render(s, rs, runtime());
    rs.balance = Balance::measured;
    const RenderResult measured = render(s, rs, runtime());
    const RenderResult again = render(s, rs, runtime());
    expect_same_image_other_banks(facets, measured, pes);
    EXPECT_EQ(measured.stats.balance, Balance::measured);
    EXPECT_EQ(measured.stats.pilot_frames, kPilotFrames);
    EXPECT_GT(occupancy(measured.stats), occupancy(facets.stats) + 0.1) << pes << " PEs";
    EXPECT_EQ(measured.stats.bank_bytes, again.stats.bank_bytes) << "the pilots chose another partition";
    EXPECT_EQ(measured.stats.counters, again.stats.counters);
  }
}

// A whole scene the caller may change lends its facets out while the
// pilots' view is copied (no second copy of them), and gets them back: the
// same buffer, and the same banks as the pilots of a const scene, whose view
// is a full copy. The view keeps the scene's bounds, so the pilot frames'
// epsilon, and with it every count, are the copy's. The bench's warm-up
// frame changes nothing either. (Not in the Pilot
// suite: Oclgrind runs that one, and ten pilot frames of hundreds are far
// too slow there.)
TEST(PilotView, AWholeSceneLendsItsFacetsToThePilotsView) {
  Scene s = load_scene(std::string(OPSILA_SOURCE_DIR) + "/scenes/hundreds.json");
  s.width = 96;
  s.height = 72;
  RenderSettings rs;
  rs.num_pes = 16;
  rs.balance = Balance::measured;
  const PreparedBanks copied = prepare_banks(static_cast<const Scene&>(s), rs, runtime());
  const Triangle* facets = s.triangles.data();
  const std::size_t count = s.triangles.size(), textures = s.textures.size();
  const PreparedBanks lent = prepare_banks(s, rs, runtime());
  EXPECT_EQ(s.triangles.data(), facets);
  EXPECT_EQ(s.triangles.size(), count);
  EXPECT_EQ(s.textures.size(), textures);
  EXPECT_EQ(lent.pilot_frames, kPilotFrames);
  ASSERT_EQ(lent.scene.triangles.size(), copied.scene.triangles.size());
  EXPECT_EQ(0, std::memcmp(lent.scene.triangles.data(), copied.scene.triangles.data(),
                           copied.scene.triangles.size() * sizeof(BankTriangle)));
  ASSERT_EQ(lent.scene.pes.size(), copied.scene.pes.size());
  for (std::size_t p = 0; p < copied.scene.pes.size(); ++p) {
    EXPECT_EQ(lent.scene.pes[p].tri_begin, copied.scene.pes[p].tri_begin) << "PE " << p;
    EXPECT_EQ(lent.scene.pes[p].tri_end, copied.scene.pes[p].tri_end) << "PE " << p;
  }
  EXPECT_EQ(lent.pilot_warm_up_seconds, 0.0);

  // The bench's warm-up (the first pilot frame run once more, untimed)
  // leaves the pilots' counts, so their partition, as they were.
  rs.pilot_warm_up = true;
  const PreparedBanks warmed = prepare_banks(s, rs, runtime());
  EXPECT_EQ(warmed.pilot_frames, kPilotFrames);
  EXPECT_GT(warmed.pilot_warm_up_seconds, 0.0);
  ASSERT_EQ(warmed.scene.triangles.size(), copied.scene.triangles.size());
  EXPECT_EQ(0, std::memcmp(warmed.scene.triangles.data(), copied.scene.triangles.data(),
                           copied.scene.triangles.size() * sizeof(BankTriangle)));
  ASSERT_EQ(warmed.scene.pes.size(), copied.scene.pes.size());
  for (std::size_t p = 0; p < copied.scene.pes.size(); ++p)
    EXPECT_EQ(warmed.scene.pes[p].tri_end, copied.scene.pes[p].tri_end) << "PE " << p;
}

// The pilot's counts: every test of the SPMD phase of a child box or facet
// that belongs to a cluster is counted for it at the ray's level, so the
// counted work is most of (and never above) the tests the PEs report. Small
// enough for Oclgrind (.ci/oclgrind.sh runs it with every check).
TEST(Pilot, CountsTheSpmdTestsPerClusterAndLevel) {
  Scene s = test::mirror_glass_scene(16, 4);
  RenderSettings rs;
  rs.num_pes = 4;
  rs.measure_cost = true;
  PreparedBanks banks = prepare_banks(s, rs, runtime());
  const std::vector<int> facet_cluster = banks.facet_cluster;
  Renderer pilot(s, std::move(banks), rs, runtime());
  const RenderResult r = pilot.render();
  const MeasuredWork w = spread_cluster_work(pilot.cluster_work(), s.max_depth, facet_cluster);
  ASSERT_EQ(w.levels, s.max_depth);
  ASSERT_EQ(w.per_facet.size(), s.triangles.size() * std::size_t(s.max_depth));
  for (int l = 0; l < s.max_depth; ++l) {
    double counted = 0, reported = 0;
    for (std::size_t t = 0; t < s.triangles.size(); ++t) counted += w.per_facet[t * w.levels + l];
    for (const auto& pe : r.stats.counters[std::size_t(l)])
      reported += double(pe[OPSILA_STAT_TRI_TESTS] + pe[OPSILA_STAT_BOX_TESTS]);
    EXPECT_LE(counted, reported * 1.0001 + 1) << "level " << l;
    EXPECT_GT(counted, 0.5 * reported) << "level " << l << ": most tests lie below the cluster roots";
  }
  // The renderer without the pilot's program counts nothing.
  RenderSettings plain;
  plain.num_pes = 8;
  Renderer frame(s, prepare_banks(s, plain, runtime()), plain, runtime());
  frame.render();
  EXPECT_TRUE(frame.cluster_work().empty());
}

TEST(Renderer, NoRayLostWithTinyBanks) {
  Scene s = test::mirror_glass_scene(40);
  RenderResult base = render_with(s, 4);
  for (int capacity : {1, 2, 7}) {
    RenderResult r = render_with(s, 4, capacity);
    EXPECT_EQ(r.stats.bank_capacity, capacity);
    expect_balanced(r.stats);
    EXPECT_GT(r.stats.overflow_deferrals, 0u) << "capacity " << capacity << " should overflow";
    EXPECT_GE(test::clamped_psnr(r.rgb, base.rgb), 60.0) << "capacity " << capacity;
  }
}

// How many work-groups serve a bank, how large the banks are, and how the
// slots are shared out change the rounds, never the bytes of the image.
TEST(Renderer, ByteIdenticalAcrossLaunchGeometry) {
  Scene s = test::mirror_glass_scene(48);
  const RenderResult base = render_with(s, 16);
  struct Geometry {
    int pes, capacity, groups_per_pe;
  };
  for (const Geometry g : {Geometry{16, 0, 1}, Geometry{16, 0, 2}, Geometry{16, 3, 0}, Geometry{16, 1, 1},
                           Geometry{16, 40, 3}, Geometry{4, 0, 0}, Geometry{1, 0, 0}, Geometry{64, 2, 1}}) {
    RenderSettings rs;
    rs.num_pes = g.pes;
    rs.bank_capacity = g.capacity;
    rs.work_groups_per_pe = g.groups_per_pe;
    const RenderResult r = render(s, rs, runtime());
    SCOPED_TRACE(std::to_string(g.pes) + " PEs, capacity " + std::to_string(g.capacity) + ", " +
                 std::to_string(g.groups_per_pe) + " work-groups per PE");
    ASSERT_EQ(r.rgb.size(), base.rgb.size());
    EXPECT_EQ(0, std::memcmp(r.rgb.data(), base.rgb.data(), r.rgb.size() * sizeof(float)));
    EXPECT_EQ(r.item_buffer, base.item_buffer);
    expect_balanced(r.stats);
  }
}

TEST(Renderer, BitIdenticalRunToRun) {
  Scene s = test::mirror_glass_scene(80);
  RenderResult a = render_with(s, 16);
  RenderResult b = render_with(s, 16);
  ASSERT_EQ(a.rgb.size(), b.rgb.size());
  EXPECT_EQ(0, std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)));
  EXPECT_EQ(a.item_buffer, b.item_buffer);
}

// A prepared machine renders frame after frame (the bench's repeats): each
// frame starts from zero counters, writes its pixel sums afresh (its first
// hit list: nothing of the frame before is left in them) and ends with the
// same image and the same statistics as a fresh one.
TEST(Renderer, PreparedOnceRendersEqualFrames) {
  Scene s = test::mirror_glass_scene(64);
  RenderSettings rs;
  rs.num_pes = 4;
  rs.bank_capacity = 32;
  Renderer machine(s, prepare_banks(s, rs, runtime()), rs, runtime());
  RenderResult first = machine.render();
  RenderResult second = machine.render();
  RenderResult fresh = render_with(s, 4, 32);
  // Into a result that already holds a frame, and one of another size: its
  // storage is reused or resized, and nothing of the old frame is left.
  RenderResult reused = first, resized = render_with(test::mirror_glass_scene(40), 4, 32);
  std::fill(reused.rgb.begin(), reused.rgb.end(), -1.0f);
  std::fill(reused.item_buffer.begin(), reused.item_buffer.end(), 7);
  reused.stats.rounds += 5;
  machine.render(reused);
  machine.render(resized);
  EXPECT_EQ(resized.width, first.width);
  EXPECT_EQ(resized.rays.total(), first.rays.total());
  EXPECT_EQ(reused.rays.total(), first.rays.total());
  for (const RenderResult* r : {&second, &fresh, &reused, &resized}) {
    ASSERT_EQ(first.rgb.size(), r->rgb.size());
    EXPECT_EQ(0, std::memcmp(first.rgb.data(), r->rgb.data(), first.rgb.size() * sizeof(float)));
    EXPECT_EQ(first.item_buffer, r->item_buffer);
    EXPECT_EQ(first.stats.counters, r->stats.counters);
    EXPECT_EQ(first.stats.traffic, r->stats.traffic);
    EXPECT_EQ(first.stats.rounds, r->stats.rounds);
  }
  expect_balanced(second.stats);
}

// A frame asked for no item buffer (a render without --item-buffer, the
// bench) keeps only the hits it needs: no centre pass for an even sample
// grid, no (object, facet) output, and on one device the item buffer traces
// only the tiles that overlap a cluster's rectangle (none when the view
// meets no cluster): the hit list counts the pixels outside as misses. The
// image, the rays and the work are the same as with it, facing the scene,
// from far (most tiles outside) and turned away (no tile traced).
TEST(Renderer, WithoutTheItemBufferOutputTheImageIsTheSame) {
  auto passes = [](const RenderResult& r) {
    int n = 0;
    for (const LaunchRecord& l : r.stats.launches) n += l.name == "item_buffer";
    return n;
  };
  const Scene facing = test::mirror_glass_scene(40);
  Scene far = facing, away = facing;
  for (int i = 0; i < 3; ++i) {
    far.camera.eye[i] = facing.camera.look_at[i] + 4 * (facing.camera.eye[i] - facing.camera.look_at[i]);
    away.camera.look_at[i] = 2 * facing.camera.eye[i] - facing.camera.look_at[i];
  }
  for (const Scene* view : std::initializer_list<const Scene*>{&facing, &far, &away})
    for (int spp : {1, 4}) {
      Scene s = *view;
      s.spp = spp;
      const std::string what = (view == &facing ? "facing" : view == &far ? "far" : "away") + std::string(", spp ") +
                               std::to_string(spp);
      RenderSettings rs;
      rs.num_pes = 16;
      const RenderResult with = render(s, rs, runtime());
      rs.item_buffer_output = false;
      const RenderResult without = render(s, rs, runtime());
      EXPECT_EQ(with.item_buffer.size(), std::size_t(2) * s.width * s.height) << what;
      EXPECT_TRUE(without.item_buffer.empty()) << what;
      ASSERT_EQ(with.rgb.size(), without.rgb.size());
      EXPECT_EQ(0, std::memcmp(with.rgb.data(), without.rgb.data(), with.rgb.size() * sizeof(float))) << what;
      EXPECT_TRUE(with.rays.same_rays(without.rays)) << what;
      EXPECT_EQ(with.stats.counters, without.stats.counters) << what;
      // One launch a pass here (a small image): the centre pass is the one
      // left out; turned away, no pass traces anything.
      EXPECT_EQ(passes(with), spp == 4 ? 5 : 1) << what;
      EXPECT_EQ(passes(without), view == &away ? 0 : spp) << what;
      if (view == &far) EXPECT_GT(with.rays.primary_hits, 0u) << what;
    }
}

// The read-back a discrete GPU takes (the pixel sums read into pinned host
// memory, only the traced rectangle's rows on one device) gives the image
// the map of a CPU device gives, facing the scene, from far (a band of rows)
// and turned away (no row read), with and without the item buffer, at 1, 4
// and 9 samples (the decode's product and its division), frame after frame.
TEST(Renderer, ThePinnedReadBackGivesTheMappedImage) {
  const Scene facing = test::mirror_glass_scene(40);
  Scene far = facing, away = facing;
  for (int i = 0; i < 3; ++i) {
    far.camera.eye[i] = facing.camera.look_at[i] + 6 * (facing.camera.eye[i] - facing.camera.look_at[i]);
    away.camera.look_at[i] = 2 * facing.camera.eye[i] - facing.camera.look_at[i];
  }
  far.width = 48, far.height = 40;  // not square: rows and columns differ
  for (const Scene* view : std::initializer_list<const Scene*>{&facing, &far, &away})
    for (int spp : {1, 4, 9})
      for (bool items : {false, true}) {
        Scene s = *view;
        s.spp = spp;
        const std::string what = (view == &facing ? "facing" : view == &far ? "far" : "away") +
                                 std::string(", spp ") + std::to_string(spp) + (items ? ", items" : "");
        RenderSettings rs;
        rs.num_pes = 16;
        rs.item_buffer_output = items;
        const RenderResult mapped = render(s, rs, runtime());
        rs.pinned_readback = true;
        PreparedBanks banks = prepare_banks(s, rs, runtime());
        Renderer machine(s, std::move(banks), rs, runtime());
        for (int frame = 0; frame < 2; ++frame) {
          const RenderResult pinned = machine.render();
          ASSERT_EQ(mapped.rgb.size(), pinned.rgb.size()) << what;
          EXPECT_EQ(0, std::memcmp(mapped.rgb.data(), pinned.rgb.data(), mapped.rgb.size() * sizeof(float)))
              << what << ", frame " << frame;
          EXPECT_EQ(mapped.item_buffer, pinned.item_buffer) << what;
        }
      }
}

// Brute force: every facet against every primary ray, no acceleration.
TEST(Renderer, ItemBufferEqualsBruteForcePrimaryRays) {
  Scene s = test::mirror_glass_scene(72);
  RenderResult r = render_with(s, 16);
  std::size_t agree = 0;
  test::for_each_primary_ray(s, [&](int x, int y, const Vec3& d) {
    const Vec3& o = s.camera.eye;
    double best = INFINITY;
    int obj = -1, facet = -1;
    for (const Triangle& t : s.triangles) {
      double e1[3], e2[3], pv[3], tv[3], qv[3];
      for (int a = 0; a < 3; ++a) e1[a] = double(t.v1[a]) - t.v0[a], e2[a] = double(t.v2[a]) - t.v0[a];
      pv[0] = d[1] * e2[2] - d[2] * e2[1], pv[1] = d[2] * e2[0] - d[0] * e2[2], pv[2] = d[0] * e2[1] - d[1] * e2[0];
      double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
      if (std::fabs(det) < 1e-12) continue;
      for (int a = 0; a < 3; ++a) tv[a] = double(o[a]) - t.v0[a];
      double u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) / det;
      if (u < 0 || u > 1) continue;
      qv[0] = tv[1] * e1[2] - tv[2] * e1[1], qv[1] = tv[2] * e1[0] - tv[0] * e1[2], qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
      double v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) / det;
      if (v < 0 || u + v > 1) continue;
      double tt = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det;
      if (tt > 0 && tt < best) best = tt, obj = t.object_id, facet = t.facet_id;
    }
    std::size_t i = 2 * (std::size_t(y) * s.width + x);
    agree += (r.item_buffer[i] == obj && r.item_buffer[i + 1] == facet);
  });
  EXPECT_GE(double(agree) / (s.width * s.height), 0.999);
}

TEST(Renderer, StatsCountPerLevelAndPe) {
  Scene s = test::mirror_glass_scene(64);
  RenderResult r = render_with(s, 16);
  const RenderStats& st = r.stats;
  ASSERT_EQ(st.counters.size(), std::size_t(s.max_depth));
  ASSERT_EQ(st.counters[0].size(), 16u);
  std::uint64_t level0 = 0, level1 = 0;
  for (int p = 0; p < 16; ++p) {
    level0 += st.counters[0][p][OPSILA_STAT_TRACED];
    level1 += st.counters[1][p][OPSILA_STAT_TRACED];
  }
  EXPECT_GE(level0, r.rays.primary_hits);  // every primary hit is shaded once, forwards on top
  EXPECT_GT(level1, 0u);
  EXPECT_EQ(st.bank_bytes.size(), 16u);
  EXPECT_GT(st.replicated_bytes, *std::max_element(st.bank_bytes.begin(), st.bank_bytes.end()));
  bool saw_spmd = false, saw_scatter = false, saw_item = false;
  for (auto& l : st.launches) {
    saw_spmd |= l.name == "spmd_phase";
    saw_scatter |= l.name == "scatter_move";
    saw_item |= l.name == "item_buffer";
    EXPECT_GE(l.seconds, 0.0);
  }
  EXPECT_TRUE(saw_spmd && saw_scatter && saw_item);
}

}  // namespace
}  // namespace opsila
