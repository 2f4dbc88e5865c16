/* SIMD scatter: Vd(I'(i)) = Vs(i). The source vector is the SPMD output area
 * (P*n*S fixed slots, NIL holes included) followed by the waiting queue.
 * The destination field gives I; I' is made injective by a stable counting
 * sort on the destination PE: rank(i) = number of earlier valid entries
 * bound for the same PE. Entry i goes to bank dest(i), slot rank(i), when
 * rank(i) < n; otherwise it waits in the next queue (no ray is lost).
 *
 * Three passes, each a plain data-parallel kernel:
 *   scatter_count: per block of SCATTER_BLOCK entries, per-PE counts and
 *                  the rank of each entry inside its block;
 *   scatter_scan:  per PE, exclusive prefix over blocks, and PE totals;
 *   scatter_plan:  bank fill counts and the queue layout of the overflow;
 *   scatter_move:  moves every field of every valid entry to I'(i). */
#include "lib/descriptor.cl"

#define SCATTER_BLOCK OPSILA_SCATTER_BLOCK

/* Destination of source entry k, or -1 for a hole. */
inline int source_dest(int k, int out_len, int n, int S, __global const int *processed_count,
                       __global const int *out_dest, __global const int *q_dest) {
  if (k < out_len) {
    int slot = k / S;
    int pe = slot / n;
    if (slot - pe * n >= processed_count[pe]) return -1; /* slot not used this phase */
    return out_dest[k];
  }
  return q_dest[k - out_len];
}

__kernel void scatter_count(int out_len, int queue_len, int n, int S, int num_pes,
                            __global const int *processed_count, __global const int *out_dest,
                            __global const int *q_dest, __global int *block_hist, __global int *rank) {
  int b = get_global_id(0);
  int total = out_len + queue_len;
  int begin = b * SCATTER_BLOCK;
  if (begin >= total) return;
  int end = min(begin + SCATTER_BLOCK, total);
  __global int *hist = block_hist + (long)b * num_pes;
  for (int q = 0; q < num_pes; ++q) hist[q] = 0;
  for (int k = begin; k < end; ++k) {
    int d = source_dest(k, out_len, n, S, processed_count, out_dest, q_dest);
    if (d >= 0 && d < num_pes) {
      rank[k] = hist[d]++;
    } else {
      rank[k] = -1;
    }
  }
}

__kernel void scatter_scan(int num_blocks, int num_pes, __global int *block_hist, __global int *pe_total) {
  int q = get_global_id(0);
  if (q >= num_pes) return;
  int running = 0;
  for (int b = 0; b < num_blocks; ++b) {
    long at = (long)b * num_pes + q;
    int h = block_hist[at];
    block_hist[at] = running;
    running += h;
  }
  pe_total[q] = running;
}

/* counts[0] = entries left waiting (next queue length),
 * counts[1] = entries placed in banks this round. */
__kernel void scatter_plan(int num_pes, int n, __global const int *pe_total, __global int *bank_count,
                           __global int *overflow_base, __global int *counts) {
  if (get_global_id(0) != 0) return;
  int waiting = 0, placed_all = 0;
  for (int q = 0; q < num_pes; ++q) {
    int placed = min(pe_total[q], n);
    bank_count[q] = placed;
    overflow_base[q] = waiting;
    waiting += pe_total[q] - placed;
    placed_all += placed;
  }
  counts[0] = waiting;
  counts[1] = placed_all;
}

/* One launch per source segment (SPMD outputs, then the queue), so that
 * every work-item of a launch reads the same buffers: straight loads that
 * vectorising compilers keep as such. Global entry index = rank_offset + k. */
__kernel void scatter_move(int src_len, int rank_offset, int n, int S, int num_pes, int from_outputs,
                           DESC_PARAMS(s), __global const int *rank, __global const int *block_hist,
                           __global const int *overflow_base, DESC_PARAMS(b), DESC_PARAMS(w),
                           volatile __global uint *traffic, int traffic_levels) {
  int k = get_global_id(0);
  if (k >= src_len) return;
  int g = rank_offset + k;
  int rk = rank[g];
  if (rk < 0) return;
  int d = s_dest[k];
  int r = block_hist[(long)(g / SCATTER_BLOCK) * num_pes + d] + rk;
  float4 org = s_org[k], dir = s_dir[k], wgt = s_wgt[k];
  int4 ids = s_ids[k];
  if (from_outputs && traffic_levels > 0) {
    int level = OPSILA_META_LEVEL(ids.y);
    int from_pe = (k / S) / n;
    if (level < traffic_levels) atomic_inc(&traffic[((long)level * num_pes + from_pe) * num_pes + d]);
  }
  bool in_bank = r < n;
  int at = in_bank ? d * n + r : overflow_base[d] + (r - n);
  __global float4 *to_org = in_bank ? b_org : w_org;
  __global float4 *to_dir = in_bank ? b_dir : w_dir;
  __global float4 *to_wgt = in_bank ? b_wgt : w_wgt;
  __global int4 *to_ids = in_bank ? b_ids : w_ids;
  __global int *to_dest = in_bank ? b_dest : w_dest;
  to_org[at] = org;
  to_dir[at] = dir;
  to_wgt[at] = wgt;
  to_ids[at] = ids;
  to_dest[at] = d;
}
