// Device buffers of the frame machine: the scene's banks and global tables
// (uploaded once), the frame's buffers, and their clearing between frames.
#include "machine/frame.h"

#include <algorithm>
#include <cmath>

#include "core/camera.h"
#include "core/texture.h"
#include "machine/counters.h"

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
std::vector<cl_int4> cluster_rects(const Scene& scene, const BankedScene& bs) {
  const CameraFrame frame = camera_frame(scene.camera, scene.width, scene.height);
  int W = scene.width, H = scene.height;
  std::vector<cl_int4> rects(bs.clusters.size());
  for (std::size_t c = 0; c < bs.clusters.size(); ++c) {
    const Cluster& cl = bs.clusters[c];
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

SurfaceBuffers upload_surface(ClRuntime& rt, const BankedScene& bs) {
  SurfaceBuffers b;
  b.attributes = upload(rt, bs.attributes, "vertex attributes");
  b.textures = upload(rt, bs.textures, "texture copies");
  b.texels = upload(rt, bs.texels, "texels");
  const std::array<float, 256>& table = srgb_decode_table();
  b.srgb = upload(rt, std::vector<float>(table.begin(), table.end()), "sRGB decode table");
  return b;
}

// Scene: banks and the global (every-PE) tables, uploaded once.
void Renderer::Machine::upload_scene(const Scene& scene, const BankedScene& bs) {
  b_tris = upload(rt, bs.triangles, "bank facets");
  b_nodes = upload(rt, bs.nodes, "bank BVH nodes");
  b_clusters = upload(rt, bs.clusters, "cluster spheres");
  b_route = upload(rt, bs.route_nodes, "routing boxes");
  b_pes = upload(rt, bs.pes, "PE table");
  b_mats = upload(rt, bs.materials, "materials");
  std::vector<Light> lights = bs.lights;
  if (lights.empty()) lights.push_back(Light{});
  b_lights = upload(rt, lights, "lights");
  surface = upload_surface(rt, bs);
  std::vector<cl_int4> rects = cluster_rects(scene, bs);
  for (std::size_t c = 0; c < rects.size(); ++c)  // another rank's cluster: never listed here
    if (bs.clusters[c].root < 0) rects[c] = kNeverListed;
  b_rects = upload(rt, rects, "projected cluster boxes");
  // Only the pilot's program reads these; others get one-entry stand-ins.
  b_node_cluster = upload(rt, measure ? bs.node_cluster : std::vector<int>{-1}, "node clusters");
  b_tri_cluster = upload(rt, measure ? bs.tri_cluster : std::vector<int>{-1}, "facet clusters");
}

// Item buffer, pixel sums, statistics and descriptor vectors: banks (the
// slots in flight, each bank padded to whole work-groups), SPMD output
// places, and the waiting pool (ping-pong).
void Renderer::Machine::allocate_frame_buffers() {
  b_items = device_buffer(rt, npix * sizeof(cl_int2), "item buffer");
  b_item_tri = device_buffer(rt, npix * sizeof(cl_int), "item buffer hits");
  b_item_t = device_buffer(rt, npix * sizeof(cl_float), "item buffer distances");
  b_item_facet = device_buffer(rt, npix * sizeof(cl_int), "item buffer facets");
  b_accum = device_buffer(rt, npix * OPSILA_ACCUM_WORDS * sizeof(cl_uint), "pixel sums");
  nstats = std::size_t(OPSILA_MAX_DEPTH) * P * OPSILA_STAT_COUNT;
  b_stats = device_buffer(rt, counter_bytes(nstats), "stats");
  ntraffic = std::max<std::size_t>(1, std::size_t(traffic_levels) * P * P);
  b_traffic = device_buffer(rt, counter_bytes(ntraffic), "traffic");
  b_hits = device_buffer(rt, counter_bytes(1), "primary hit count");
  b_cost = device_buffer(rt, ncost * sizeof(cl_uint), "cluster work");
  b_out_count = device_buffer(rt, flight.groups * flight.group_size * sizeof(cl_int), "SPMD output counts");
  banks.allocate(rt, flight.slots + std::size_t(P) * flight.group_size, "descriptor banks");
  outputs.allocate(rt, flight.outputs, "SPMD output places");
  pool.allocate(rt, flight.pool, "descriptor pool");
  next_pool.allocate(rt, flight.pool, "descriptor pool");
}

// Every frame starts from zero pixel sums, statistics and traffic.
void Renderer::Machine::clear_frame() {
  if (rank_exchange) rank_exchange->reset();
  zero_buffer(rt, b_accum, npix * OPSILA_ACCUM_WORDS * sizeof(cl_uint), "pixel sums");
  zero_buffer(rt, b_stats, counter_bytes(nstats), "stats");
  zero_buffer(rt, b_traffic, counter_bytes(ntraffic), "traffic");
  zero_buffer(rt, b_hits, counter_bytes(1), "primary hit count");
  zero_buffer(rt, b_cost, ncost * sizeof(cl_uint), "cluster work");
}

}  // namespace opsila
