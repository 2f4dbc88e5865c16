// The scene's device arrays that the frame's kernels and the bench's
// baselines read alike, a handle type each (device/kernel_args.h), in the
// groups that travel together as kernel arguments.
#pragma once

#include <tuple>

#include "device/kernel_args.h"

namespace opsila {

struct BankedScene;

// A bank's BVH nodes and facets (partition/banks.h), and the instance
// table (one placeholder entry when the scene has none), in this order.
using BankNodes = DeviceArray<struct BankNodesRole>;
using BankFacets = DeviceArray<struct BankFacetsRole>;
using InstanceTable = DeviceArray<struct InstanceTableRole>;
struct BankGeometry {
  BankNodes nodes;
  BankFacets tris;
  InstanceTable insts;
  auto kernel_args() const { return std::tie(nodes, tris, insts); }
};

// The bank data shading reads besides facets and materials (the kernels'
// SURFACE_PARAMS): vertex attributes, texture copies, texels, and the sRGB
// decode table. Empty parts are one-element placeholders never read.
struct SurfaceBuffers {
  DeviceArray<struct SurfaceAttributesRole> attributes;
  DeviceArray<struct SurfaceTexturesRole> textures;
  DeviceArray<struct SurfaceTexelsRole> texels;
  DeviceArray<struct SrgbTableRole> srgb;
  auto kernel_args() const { return std::tie(attributes, textures, texels, srgb); }
};
SurfaceBuffers upload_surface(ClRuntime& rt, const BankedScene& bs);

// What shading reads: materials, lights (at least one), the surface.
using MaterialTable = DeviceArray<struct MaterialTableRole>;
using LightTable = DeviceArray<struct LightTableRole>;
struct ShadingTables {
  MaterialTable materials;
  LightTable lights;
  SurfaceBuffers surface;
  auto kernel_args() const { return std::tie(materials, lights, surface); }
};

}  // namespace opsila
