#include "partition/bank_qnode.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/parallel.h"

namespace opsila {

namespace {

constexpr int kWidth = OPSILA_BVH_WIDTH;
constexpr double kGridPoints = 16777216.0;  // 2^24: a grid point's multiple of the step is a float's

// One axis's grid: origin a multiple of 2^e, the finest step that covers
// [lo, hi] in 255 steps with every grid point a float. Done in doubles,
// where each of these values is exact.
struct Grid {
  float origin = 0;
  int e = 0;
};

Grid axis_grid(double lo, double hi) {
  const double extent = std::max(std::fabs(lo), std::fabs(hi));
  int e = -126;  // a normal float step
  if (hi > lo) e = std::max(e, std::ilogb((hi - lo) / 255.0));
  if (extent > 0) e = std::max(e, std::ilogb(extent) - 23);
  for (; e <= 127; ++e) {
    const double step = std::ldexp(1.0, e), m = std::floor(lo / step);
    if (std::ceil((hi - m * step) / step) <= 255.0 && std::fabs(m) + 255.0 <= kGridPoints)
      return Grid{static_cast<float>(m * step), e};
  }
  throw std::logic_error("quantise_node: no grid holds a finite box");
}

const float* plane(const BankNode& n, int axis, bool hi) {
  const float* lo_planes[3] = {n.lo_x, n.lo_y, n.lo_z};
  const float* hi_planes[3] = {n.hi_x, n.hi_y, n.hi_z};
  return hi ? hi_planes[axis] : lo_planes[axis];
}

opsila_u8* plane(BankQNode& n, int axis, bool hi) {
  opsila_u8* lo_planes[3] = {n.lo_x, n.lo_y, n.lo_z};
  opsila_u8* hi_planes[3] = {n.hi_x, n.hi_y, n.hi_z};
  return hi ? hi_planes[axis] : lo_planes[axis];
}

}  // namespace

BankQNode quantise_node(const BankNode& node) {
  BankQNode q{};
  for (int k = 0; k < kWidth; ++k) q.child[k] = node.child[k], q.count[k] = node.count[k];
  for (int a = 0; a < 3; ++a) {
    const float *lo = plane(node, a, false), *hi = plane(node, a, true);
    double box_lo = INFINITY, box_hi = -INFINITY;
    for (int k = 0; k < kWidth; ++k)
      if (node.count[k] >= 0) box_lo = std::min(box_lo, double(lo[k])), box_hi = std::max(box_hi, double(hi[k]));
    const Grid g = box_lo <= box_hi ? axis_grid(box_lo, box_hi) : Grid{};
    q.origin[a] = g.origin;
    q.exponent[a] = static_cast<opsila_u8>(g.e + 127);
    const double step = std::ldexp(1.0, g.e);
    opsila_u8 *qlo = plane(q, a, false), *qhi = plane(q, a, true);
    for (int k = 0; k < kWidth; ++k) {
      if (node.count[k] < 0) {
        qlo[k] = 255, qhi[k] = 0;  // inverted
        continue;
      }
      qlo[k] = static_cast<opsila_u8>(std::floor((double(lo[k]) - g.origin) / step));
      qhi[k] = static_cast<opsila_u8>(std::ceil((double(hi[k]) - g.origin) / step));
    }
  }
  return q;
}

BankArray<BankQNode> quantise_nodes(const BankArray<BankNode>& nodes) {
  BankArray<BankQNode> out(nodes.size());
  parallel_for(nodes.size(), [&](std::size_t i) { out[i] = quantise_node(nodes[i]); });
  return out;
}

void quantised_box(const BankQNode& node, int k, float lo[3], float hi[3]) {
  const opsila_u8* lo_planes[3] = {node.lo_x, node.lo_y, node.lo_z};
  const opsila_u8* hi_planes[3] = {node.hi_x, node.hi_y, node.hi_z};
  for (int a = 0; a < 3; ++a) {
    const float step = std::ldexp(1.0f, int(node.exponent[a]) - 127);
    lo[a] = float(lo_planes[a][k]) * step + node.origin[a];
    hi[a] = float(hi_planes[a][k]) * step + node.origin[a];
  }
}

}  // namespace opsila
