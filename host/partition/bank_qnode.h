// The bank BVH's nodes quantised for the walks of a device that reads them
// so (BankQNode, kernels/opsila_shared.h; ClRuntime::quantised_nodes): each
// BankNode becomes one BankQNode at the same index, its child boxes rounded
// outwards to an exact 8-bit grid of the node's own, so every box the walks
// test holds the float box they would have tested.
#pragma once

#include <cstddef>

#include "partition/bank_array.h"
#include "opsila_shared.h"

namespace opsila {

BankQNode quantise_node(const BankNode& node);
BankArray<BankQNode> quantise_nodes(const BankArray<BankNode>& nodes);

// Child k's box as the device decodes it (q * step + origin, in float):
// lo[3], hi[3]. Inverted on every axis for an empty slot.
void quantised_box(const BankQNode& node, int k, float lo[3], float hi[3]);

}  // namespace opsila
