// Instances (scenes/FORMAT.md, "instances"): a model's triangles held once
// and placed at many transforms. One home for what every part reads of
// them: the transform and its inverse as the kernels apply it, an
// instance's world box, and the triangles they stand for.
#pragma once

#include <array>
#include <cstdint>

#include "core/vec.h"
#include "scene/scene.h"

namespace opsila {

// Largest number of instances in one scene: the object ids are 32-bit
// (instance i is object num_objects + i), and 2^26 keeps the global tables
// every PE holds (a cluster, a placement and a routing box each, about 250
// bytes an instance) within a few GB.
constexpr std::size_t kMaxInstances = std::size_t(1) << 26;
// What an instance costs the host while preparing, in triangles of the
// memory plan's budget (scene/triangle_limit.h, 120 bytes each): its
// placement, cluster, routing and item-buffer records and its share of its
// bank's instance BVH, measured at 530 bytes an instance (docs/DISTRIBUTED.md,
// "Cost model").
constexpr std::size_t kInstanceTriangles = 6;

// An instance of `prototype` placed by `to_world` (row-major 3 x 4): its
// inverse is computed in double and rounded to float, the matrix the rays
// use. Throws InputError("<where>: ...") when the transform is singular or
// its inverse overflows float.
InstanceDesc make_instance(int prototype, const std::array<double, 12>& to_world, const std::string& where);

// A point or vector through a row-major 3 x 4 float matrix, each sum taken
// left to right in float: what kernels/lib/geometry.cl instance_ray does.
Vec3 apply_point(const std::array<float, 12>& m, const Vec3& p);
Vec3 apply_vector(const std::array<float, 12>& m, const Vec3& v);
// A model-frame normal in the world: A^T n with A = to_object's 3 x 3,
// not normalised (kernels/lib/shading.cl instance_normal).
Vec3 instance_normal(const std::array<float, 12>& to_object, const Vec3& n);

// The world box of an instance's facets as the scene's bounds count them
// (the framing, epsilon: CONTRACT "Shading"): its prototype's box through
// to_world, every corner in double, each bound rounded to the nearest
// float. For a translation or a scale, the box of the same facets placed
// without an instance; under a rotation, the box of the turned model box.
void instance_box(const Scene& scene, const InstanceDesc& in, Vec3& lo, Vec3& hi);
// The box the walks test for it: the same widened by a relative 2^-16 of
// its size and of its magnitude, so that it holds every point a ray meets
// in the model's frame through the float inverse. Not the scene's bounds:
// at 1e6 from the origin the widening is some 15 units, which had framed
// and sized epsilon for a box far larger than the facets.
void instance_holding_box(const Scene& scene, const InstanceDesc& in, Vec3& lo, Vec3& hi);

// The triangles the instances stand for (each its prototype's).
std::uint64_t instanced_triangles(const Scene& scene);
// The prototypes' triangles, once each.
std::uint64_t prototype_triangles(const Scene& scene);

}  // namespace opsila
