// The ray sample of --balance work (scene/ray_sample.h), traced by the
// reference tracer, level by level, and joined over the holders of a scene
// read in shares in the hit order (kernels/hit_order.h).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "reference/tracer_impl.h"

namespace opsila {

namespace {

// A ray of the sample, waiting to be traced.
struct SampleRay {
  Vec3 origin, direction;
  float t_min;
};

// What the holder of a ray's hit adds for it: a shadow segment (slot: the
// light's index; t: the light's distance), or a reflected (slot: lights)
// or transmitted (lights + 1) ray of the next level (t: its t_min).
struct SampleSpawn {
  std::uint32_t ray, slot;
  Vec3 origin, direction;
  float t;
};
static_assert(std::is_trivially_copyable<SampleSpawn>::value, "sent as bytes");

constexpr std::uint64_t kNoHit = ~std::uint64_t(0);
// Rays of a level traced, joined and spawned at once (sample_rays).
constexpr std::size_t kSampleChunk = std::size_t(1) << 14;

using Impl = ReferenceTracer::Impl;

// The least hit over every holder, in the hit order: the least cell of t
// (into t_bits), then (a scene with instances, which every holder has
// alike) the least instance, then the least (facet, fan) key, then (should
// two holders share a facet or an instance) the lowest holder. Each round
// keeps the rays whose hit is still the least. Returns each ray's holder.
std::vector<std::uint64_t> join_least(const Impl& im, const std::vector<Hit>& hits, const SampleJoin* join,
                                      std::uint64_t me, std::vector<std::uint64_t>& t_bits) {
  const std::size_t n = hits.size();
  std::vector<bool> least(n);
  for (std::size_t i = 0; i < n; ++i) least[i] = hits[i].tri >= 0;
  std::vector<std::uint64_t> key(n);
  const auto round = [&](auto key_of) {
    for (std::size_t i = 0; i < n; ++i) key[i] = least[i] ? key_of(hits[i]) : kNoHit;
    if (join) join->min(key);
    for (std::size_t i = 0; i < n; ++i) least[i] = least[i] && key_of(hits[i]) == key[i];
  };
  round([](const Hit& h) { return std::uint64_t(hit_grid(h.t)); });
  t_bits = key;
  // -1 (the scene's own facets) first.
  if (!im.scene.instances.empty()) round([](const Hit& h) { return std::uint64_t(std::int64_t(h.inst) + 1); });
  round([&](const Hit& h) { return im.sample_key(h); });
  round([&](const Hit&) { return me; });
  return key;
}

// The segments and rays that the hits this holder won spawn: a shadow
// segment per light that can contribute, then (children: the next level
// is traced) the reflected and transmitted rays.
std::vector<SampleSpawn> spawn_won(const Impl& im, const SampleRay* rays, const std::vector<Hit>& hits,
                                   const std::vector<std::uint64_t>& holder, std::uint64_t me, bool children) {
  const std::vector<LightDesc>& lights = im.scene.lights;
  const std::uint32_t nl = static_cast<std::uint32_t>(lights.size());
  std::vector<SampleSpawn> spawned;
  for (std::size_t i = 0; i < hits.size(); ++i) {
    if (holder[i] != me || hits[i].tri < 0) continue;
    const SampleRay& r = rays[i];
    const Impl::Surface s = im.surface(r.origin, r.direction, hits[i]);
    const std::uint32_t ray = static_cast<std::uint32_t>(i);
    for (std::uint32_t l = 0; l < nl; ++l) {
      SampleSpawn shadow{ray, l, s.p, {}, 0.0f};
      float n_dot_l;
      if (Impl::shadow_ray(s.p, s.n, lights[l], shadow.direction, shadow.t, n_dot_l)) spawned.push_back(shadow);
    }
    if (!children) continue;
    if (any_nonzero(s.m->kr())) spawned.push_back({ray, nl, s.p, Impl::reflected(r.direction, s.n), im.epsilon});
    SampleSpawn through{ray, nl + 1, s.p, {}, im.epsilon};
    if (any_nonzero(s.m->kt()) && Impl::transmitted(r.direction, s.n, s.entering, s.m->ni, through.direction))
      spawned.push_back(through);
  }
  return spawned;
}

// Every holder's spawns, in the rays' order (each ray's in slot order).
void gather_spawned(const SampleJoin* join, std::vector<SampleSpawn>& spawned) {
  if (!join) return;
  std::vector<unsigned char> mine(spawned.size() * sizeof(SampleSpawn));
  if (!mine.empty()) std::memcpy(mine.data(), spawned.data(), mine.size());
  const std::vector<unsigned char> all = join->all_gather(mine);
  spawned.resize(all.size() / sizeof(SampleSpawn));
  if (!spawned.empty()) std::memcpy(spawned.data(), all.data(), spawned.size() * sizeof(SampleSpawn));
  std::stable_sort(spawned.begin(), spawned.end(), [](const SampleSpawn& a, const SampleSpawn& b) {
    return a.ray < b.ray || (a.ray == b.ray && a.slot < b.slot);
  });
}

}  // namespace

RaySample ReferenceTracer::sample_rays(int target_primary, const SampleJoin* join) const {
  if (impl_->queries) throw std::logic_error("sample_rays: the sample is traced through the tracer's own BVH");
  const Scene& scene = scene_;
  const Impl& im = *impl_;
  RaySample out;
  const double pixels = double(scene.width) * double(scene.height);
  out.stride = std::max(1, static_cast<int>(std::sqrt(pixels / std::max(1, target_primary))));
  std::vector<SampleRay> level;
  for (int y = out.stride / 2; y < scene.height; y += out.stride)
    for (int x = out.stride / 2; x < scene.width && level.size() < kMaxSampleRays; x += out.stride)
      level.push_back({scene.camera.eye, primary_direction(im.frame, scene.width, scene.height, x, y), 0.0f});
  const std::uint32_t lights = static_cast<std::uint32_t>(scene.lights.size());
  const std::uint64_t me = join ? std::uint64_t(join->holder()) : 0;
  std::vector<SampleRay> next;
  for (int depth = 0; !level.empty(); ++depth) {
    // Each ray adds a segment: rays beyond the room left are not traced.
    level.resize(std::min(level.size(), kMaxSampleRays - out.rays.size()));
    const bool children = depth + 1 < scene.max_depth;
    next.clear();
    // A chunk of the level at a time, so what a holder spawns (a shadow
    // segment per light, up to 64, and two rays per hit) stays bounded.
    for (std::size_t c0 = 0; c0 < level.size() && out.rays.size() < kMaxSampleRays; c0 += kSampleChunk) {
      const SampleRay* rays = level.data() + c0;
      const std::size_t n = std::min(level.size() - c0, kSampleChunk);
      std::vector<Hit> hits(n);
      for (std::size_t i = 0; i < n; ++i) im.own_nearest(rays[i].origin, rays[i].direction, rays[i].t_min, hits[i]);
      std::vector<std::uint64_t> t_bits;
      const std::vector<std::uint64_t> holder = join_least(im, hits, join, me, t_bits);
      std::vector<SampleSpawn> spawned = spawn_won(im, rays, hits, holder, me, children);
      gather_spawned(join, spawned);

      // The chunk's segments in its rays' order, each ray's shadow segments
      // after it; the next level's rays in the same order.
      std::size_t k = 0;
      for (std::size_t i = 0; i < n && out.rays.size() < kMaxSampleRays; ++i) {
        // The hit's cell (its start): the segment ends there, within 2^-19.
        const float t = t_bits[i] == kNoHit ? OPSILA_HIT_INF : hit_bits_float(static_cast<hit_bits_t>(t_bits[i]));
        out.rays.push_back({rays[i].origin, rays[i].direction, t});
        for (; k < spawned.size() && spawned[k].ray == i; ++k) {
          const SampleSpawn& sp = spawned[k];
          if (sp.slot >= lights)
            next.push_back({sp.origin, sp.direction, sp.t});
          else if (out.rays.size() < kMaxSampleRays)
            out.rays.push_back({sp.origin, sp.direction, sp.t});
        }
      }
    }
    level.swap(next);
  }
  return out;
}

}  // namespace opsila
