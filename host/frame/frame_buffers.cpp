// Device buffers of the frame machine, declared once in its buffer table:
// the scene's banks and global tables (uploaded once), the frame's buffers,
// and those cleared between frames.
#include "frame/frame.h"

#include <algorithm>
#include <cmath>

#include "scene/camera.h"
#include "scene/texture.h"
#include "device/counters.h"
#include "partition/bank_qnode.h"

namespace opsila {

namespace {

// A rectangle that overlaps no tile: the cluster is never listed.
const cl_int4 kNeverListed{{1 << 30, 1 << 30, -(1 << 30), -(1 << 30)}};

// Every corner of the cluster's box lies behind the eye, clear of its plane
// by a margin far above rounding: no primary ray (t > 0 along a direction
// in front of the eye) can meet the box, so no pixel need test it. Without
// this such a box got the whole screen, and every pixel paid a root test
// for it (all of a pass when the view looks away from the scene).
bool entirely_behind(const CameraFrame& frame, const Cluster& cl) {
  for (int k = 0; k < 8; ++k) {
    const double d[3] = {double((k & 1) ? cl.bmax[0] : cl.bmin[0]) - frame.eye[0],
                         double((k & 2) ? cl.bmax[1] : cl.bmin[1]) - frame.eye[1],
                         double((k & 4) ? cl.bmax[2] : cl.bmin[2]) - frame.eye[2]};
    const double cz = double(frame.forward[0]) * d[0] + double(frame.forward[1]) * d[1] +
                      double(frame.forward[2]) * d[2];
    if (!(cz < -1e-4 * std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]))) return false;
  }
  return true;
}

}  // namespace

// "Projected object boxes": each cluster box as a conservative pixel
// rectangle (x0, y0, x1, y1), the whole screen when a corner is behind the
// eye, none when all of them are.
std::vector<cl_int4> cluster_rects(const Scene& scene, const std::vector<Cluster>& clusters) {
  const CameraFrame frame = camera_frame(scene.camera, scene.width, scene.height);
  int W = scene.width, H = scene.height;
  std::vector<cl_int4> rects(clusters.size());
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    const Cluster& cl = clusters[c];
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    bool behind = false;
    for (int k = 0; k < 8 && !behind; ++k) {
      Vec3 corner{(k & 1) ? cl.bmax[0] : cl.bmin[0], (k & 2) ? cl.bmax[1] : cl.bmin[1],
                  (k & 4) ? cl.bmax[2] : cl.bmin[2]};
      double px, py;
      behind = !project_to_pixels(frame, W, H, corner, px, py);
      if (behind) break;
      x0 = std::min(x0, px), x1 = std::max(x1, px), y0 = std::min(y0, py), y1 = std::max(y1, py);
    }
    cl_int4 rc;
    if (entirely_behind(frame, cl)) {
      rc = kNeverListed;
    } else if (behind || !std::isfinite(x0 + x1 + y0 + y1)) {
      rc.s[0] = 0, rc.s[1] = 0, rc.s[2] = W - 1, rc.s[3] = H - 1;
    } else {
      // One pixel of margin: the rectangle only culls, the ray test decides.
      rc.s[0] = static_cast<int>(std::max(-1.0, std::floor(x0) - 1));
      rc.s[1] = static_cast<int>(std::max(-1.0, std::floor(y0) - 1));
      rc.s[2] = static_cast<int>(std::min(double(W), std::ceil(x1) + 1));
      rc.s[3] = static_cast<int>(std::min(double(H), std::ceil(y1) + 1));
    }
    rects[c] = rc;
  }
  return rects;
}

std::vector<Cluster> item_buffer_clusters(const BankedScene& bs) {
  std::vector<Cluster> out;
  for (const PeInfo& pe : bs.pes) {
    Cluster banked{};  // the PE's instances under their BVH
    Box box;
    for (int c = pe.cluster_begin; c < pe.cluster_end; ++c) {
      const Cluster& cl = bs.clusters[std::size_t(c)];
      if (cl.root >= -1 || pe.instance_root < 0) {
        out.push_back(cl);
        continue;
      }
      box.grow(cl.bmin);
      box.grow(cl.bmax);
      banked.pe = cl.pe;
    }
    if (box.empty()) continue;
    for (int a = 0; a < 3; ++a) banked.bmin[a] = box.lo[a], banked.bmax[a] = box.hi[a];
    banked.root = pe.instance_root;
    out.push_back(banked);
  }
  return out;
}

std::vector<int> item_depth_order(const Scene& scene, const std::vector<Cluster>& clusters,
                                  std::vector<double>* distance) {
  const Vec3 eye = scene.camera.eye;
  std::vector<double> d2(clusters.size());
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    const Cluster& cl = clusters[c];
    for (int a = 0; a < 3; ++a) {
      const double out = std::max({double(cl.bmin[a]) - eye[a], double(eye[a]) - cl.bmax[a], 0.0});
      d2[c] += out * out;
    }
  }
  std::vector<int> order(clusters.size());
  for (std::size_t c = 0; c < order.size(); ++c) order[c] = static_cast<int>(c);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return d2[std::size_t(a)] < d2[std::size_t(b)]; });
  if (distance)
    for (std::size_t c = 0; c < d2.size(); ++c) (*distance).push_back(std::sqrt(d2[c]));
  return order;
}

// The union of the rectangles (empty, kNeverListed, when there are none).
cl_int4 rects_union(const std::vector<cl_int4>& rects) {
  cl_int4 u = kNeverListed;
  for (const cl_int4& r : rects) {
    u.s[0] = std::min(u.s[0], r.s[0]), u.s[1] = std::min(u.s[1], r.s[1]);
    u.s[2] = std::max(u.s[2], r.s[2]), u.s[3] = std::max(u.s[3], r.s[3]);
  }
  return u;
}

// The bench's megakernel reads the same surface tables (its own uploads).
SurfaceBuffers upload_surface(ClRuntime& rt, const BankedScene& bs) {
  SurfaceBuffers b;
  b.attributes.buffer = upload(rt, bs.attributes, "vertex attributes");
  b.textures.buffer = upload(rt, bs.textures, "texture copies");
  b.texels.buffer = upload(rt, bs.texels, "texels");
  const std::array<float, 256>& table = srgb_decode_table();
  b.srgb.buffer = upload(rt, std::vector<float>(table.begin(), table.end()), "sRGB decode table");
  return b;
}

// The host side of the uploads: the tables made for the device, and the
// bank arrays taken from the prepared banks (aligned for use in place where
// the device shares host memory).
void Renderer::Machine::host_tables(const Scene& scene, BankedScene& bs) {
  lights = bs.lights;
  if (lights.empty()) lights.push_back(Light{});
  const std::vector<Cluster> listed_clusters = item_buffer_clusters(bs);
  const std::vector<cl_int4> by_index = cluster_rects(scene, listed_clusters);
  rects.clear();
  item_clusters.clear();
  item_near.clear();
  std::vector<double> distance;
  for (int c : item_depth_order(scene, listed_clusters, &distance)) {  // another rank's (root -1): never listed here
    rects.push_back(listed_clusters[std::size_t(c)].root == -1 ? kNeverListed : by_index[std::size_t(c)]);
    item_clusters.push_back(listed_clusters[std::size_t(c)]);
    // Rounded down: a camera ray enters the box no nearer than this.
    float near = static_cast<float>(distance[std::size_t(c)]);
    if (double(near) > distance[std::size_t(c)]) near = std::nextafter(near, 0.0f);
    item_near.push_back(near);
  }
  const cl_int4 listed = item_list.listed = rects_union(rects);
  bins = item_bins(rects, width, height, tile_w);
  item_list.bin_side = bins.side;
  item_list.bins_x = bins.bins_x;
  // Several ranks relay the item buffer in bands of whole tile rows, and
  // each lists only its own clusters: they trace the whole image alike.
  traced_rect = {{0, 0, width - 1, height - 1}};
  if (group.all() && !item_output)
    traced_rect = {{std::max(listed.s[0], 0), std::max(listed.s[1], 0), std::min(listed.s[2], width - 1),
                    std::min(listed.s[3], height - 1)}};
  const std::array<float, 256>& table = srgb_decode_table();
  srgb.assign(table.begin(), table.end());
  const HostSharing sharing = host_sharing(rt);
  const std::size_t align = sharing.in_place ? sharing.alignment : 1;
  host_tris = HostArray::adopt(std::move(bs.triangles), align);
  if (rt.quantised_nodes()) {
    host_nodes = HostArray::adopt(quantise_nodes(bs.nodes), align);
    BankArray<BankNode>().swap(bs.nodes);
  } else {
    host_nodes = HostArray::adopt(std::move(bs.nodes), align);
  }
  host_attributes = HostArray::adopt(std::move(bs.attributes), align);
  host_texels = HostArray::adopt(std::move(bs.texels), align);
}

// Creates and fills the table's buffers. Copies are written without
// waiting; once they are done, the bank arrays the device does not read in
// place are freed, and the host pointers of the freed tables forgotten.
void Renderer::Machine::allocate() {
  in_place_bytes = allocate_buffers(rt, buffers);
  cl_check(rt.queue().finish(), "clFinish(uploads)");
  for (HostArray* a : {&host_tris, &host_nodes, &host_attributes, &host_texels})
    if (!in_place_bytes) *a = HostArray();
  for (BufferSpec& s : buffers)
    if (!s.host_kept || !in_place_bytes) s.host = nullptr;
}

// The frame's buffer table: every device buffer of the frame, once, in the
// order they are allocated. The memory plan is its sum (plan_of), the
// allocation and uploads follow it (allocate_buffers), and the Fill::zero
// ones are cleared before every frame.
std::vector<BufferSpec> Renderer::Machine::buffer_table(const BankedScene& bs, const FlightPlan& f) {
  using P_ = PlanPart;
  const std::size_t sint = sizeof(cl_int);
  std::vector<BufferSpec> t = {
      // Scene: the banks (read in place where the device shares host memory)
      // and the global (every-PE) tables, uploaded once.
      kept_host_buffer("bank facets", P_::scene, host_tris, &geometry.tris.buffer),
      kept_host_buffer("bank BVH nodes", P_::scene, host_nodes, &geometry.nodes.buffer),
      host_buffer("instances", P_::scene, bs.instances.empty() ? no_instance : bs.instances, &geometry.insts.buffer),
      host_buffer("cluster spheres", P_::scene, bs.clusters, &routing_tables.clusters.buffer),
      host_buffer("routing boxes", P_::scene, bs.route_nodes, &routing_tables.route.buffer),
      host_buffer("PE table", P_::scene, bs.pes, &routing_tables.pes.buffer),
      host_buffer("materials", P_::scene, bs.materials, &shading.materials.buffer),
      host_buffer("lights", P_::scene, lights, &shading.lights.buffer),
      kept_host_buffer("vertex attributes", P_::scene, host_attributes, &shading.surface.attributes.buffer),
      host_buffer("texture copies", P_::scene, bs.textures, &shading.surface.textures.buffer),
      kept_host_buffer("texels", P_::scene, host_texels, &shading.surface.texels.buffer),
      host_buffer("sRGB decode table", P_::scene, srgb, &shading.surface.srgb.buffer),
      host_buffer("projected cluster boxes", P_::scene, rects, &item_list.rects.buffer),
      host_buffer("item buffer clusters", P_::scene, item_clusters, &item_list.clusters.buffer),
      host_buffer("item buffer cluster distances", P_::scene, item_near, &item_list.near.buffer),
      host_buffer("item buffer bins", P_::scene, bins.first, &item_list.bin_first.buffer),
      host_buffer("item buffer bin lists", P_::scene, bins.list, &item_list.bin_list.buffer),
      // Only the pilot's program reads these; others get one-entry stand-ins.
      host_buffer("node clusters", P_::scene, measure ? bs.node_cluster : no_cluster, &work.node_cluster.buffer),
      host_buffer("facet clusters", P_::scene, measure ? bs.tri_cluster : no_cluster, &work.tri_cluster.buffer),
      // Item buffer (pair, triangle, distance, the hit order's (facet, fan)
      // key) and 64-bit fixed-point RGB sums.
      frame_buffer("item buffer", P_::image, sizeof(cl_int2), npix, Fill::device, &item.items.buffer),
      frame_buffer("item buffer hits", P_::image, sint, npix, Fill::device, &item.tri.buffer),
      frame_buffer("item buffer distances", P_::image, sizeof(cl_float), npix, Fill::device, &item.t.buffer),
      frame_buffer("item buffer keys", P_::image, sizeof(cl_int2), npix, Fill::device, &item.key.buffer),
      // The hit list of a sample pass (kernels/primary.cl): its pixels, the
      // hits per block of pixels (then their prefixes), and their total.
      frame_buffer("hit list", P_::image, sint, npix, Fill::device, &b_hit_pixels.buffer),
      frame_buffer("hit list blocks", P_::image, sint, ScatterPass::blocks_of(npix), Fill::device,
                   &b_hit_blocks.buffer),
      frame_buffer("hit list length", P_::other, sint, 1, Fill::device, &b_hit_total.buffer),
      // Not cleared: the frame's first hit list writes every pixel's sums.
      frame_buffer("pixel sums", P_::image, OPSILA_ACCUM_WORDS * sizeof(cl_uint), npix, Fill::device, &b_accum.buffer),
      // The image as floats, where the device resolves it (read_resolved).
      frame_buffer("image", P_::image, 3 * sizeof(cl_float), device_resolve ? npix : 1, Fill::device,
                   &b_image.buffer),
      // Counters: statistics, PE x PE traffic, primary hits; the pilots'
      // cluster work; the SPMD phase's output counts.
      frame_buffer("stats", P_::other, 1, counter_bytes(nstats), Fill::zero, &b_stats.buffer),
      frame_buffer("traffic", P_::other, 1, counter_bytes(ntraffic), Fill::zero, &b_traffic.buffer),
      frame_buffer("primary hit count", P_::other, 1, counter_bytes(1), Fill::zero, &b_hits.buffer),
      frame_buffer("cluster work", P_::other, sizeof(cl_uint), ncost, Fill::zero, &work.cost.buffer),
      frame_buffer("SPMD output counts", P_::other, sint, f.groups * f.group_size, Fill::device, &b_out_count.buffer),
  };
  // Descriptor vectors: banks (the slots in flight, each bank padded to
  // whole work-groups), SPMD output places, the waiting pool (ping-pong).
  auto descriptors = [&](const char* name, std::size_t count, DescriptorSet* set) {
    BufferSpec d = frame_buffer(name, P_::descriptors, DescriptorSet::kSlotBytes, count, Fill::device, nullptr);
    d.set = set;
    t.push_back(d);
  };
  descriptors("descriptor banks", f.slots + std::size_t(P) * f.group_size, &banks);
  descriptors("SPMD output places", f.outputs, &outputs);
  descriptors("descriptor pool", f.pool, &pool);
  descriptors("descriptor pool", f.pool, &next_pool);
  // The exchange (ScatterPass): what plan() would grow to, allocated ahead
  // (a pass ranks at most the pool and the outputs, in at most this many
  // blocks, for at most this many SPMD work-groups of all P PEs) ...
  const ScatterPass::Needs most = ScatterPass::needs(f.pool + f.outputs, ScatterPass::blocks_of(f.pool) + f.groups,
                                                     f.slots, f.group_size, P);
  for (const ScatterPass::Table& s : scatter->grown_tables(most)) {
    BufferSpec d = frame_buffer(s.name, P_::other, sint, s.ints, Fill::device, s.buffer);
    d.capacity = s.capacity;
    t.push_back(d);
  }
  // ... and the tables it allocates when it is made.
  for (const ScatterPass::Table& s : scatter->own_tables())
    t.push_back(frame_buffer(s.name, P_::other, sint, s.ints, Fill::device, nullptr));
  return t;
}

// Every frame starts from zero statistics, traffic and work (and the pixel
// sums its first hit list writes).
void Renderer::Machine::clear_frame() {
  if (rank_exchange) rank_exchange->reset();
  zero_frame_buffers(rt, buffers);
}

}  // namespace opsila
