/* SIMD exchange: Vd(I'(i)) = Vs(i). The source vector is the SPMD outputs
 * (one run of out_item_count[t] records per SPMD work-item t, at t*S)
 * followed by the waiting pool (pool_len records, NIL holes allowed). The
 * destination field gives I; I' is made injective by a stable counting sort
 * on the entry's key (OPSILA_STREAM_KEY: 2 x its destination PE, + 1 when it
 * can still spawn radiance rays): rank(i) = number of earlier valid entries
 * with the same key. Per PE, the entries of key 2d take the bank's first
 * slots, then those of key 2d + 1; what finds no slot waits in the next pool
 * (no ray is lost). Only the records that exist are read: empty output
 * places never are. The count reads only the dense key stream (DESC_PARAMS),
 * 4 bytes a descriptor; the move reads and writes each record once.
 *
 * The order bounds the records that wait. The sequential tracer holds one
 * ray tree's path at a time; a wavefront that took the oldest records first
 * would hold a whole level of every tree (2^depth records a pixel for two
 * facing glass slabs). So:
 *   - newest first: a bank takes what its PE's last phase spawned before
 *     older records, and what waits keeps that order (per PE and key, the
 *     outputs left over, then the older pool), so the trees are worked depth
 *     first; new primary descriptors join the pool's end;
 *   - what ends its tree first: shadow rays and rays of the last level
 *     (key 2d) spawn no radiance ray, so they can only shrink what waits;
 *   - throttle: while more than the frame's planned pool waits, a bank
 *     takes only such records, as long as any PE of this device has one.
 *     Depth first alone does not bound a PE that many others feed (its
 *     records wait while theirs make more); the throttle holds the feeders
 *     until it catches up. Rays that end their tree make every round
 *     progress, and with none left the round is not throttled.
 * None of this changes the image: the pixel sums are exact whatever the
 * order (fixed point).
 *
 * With several devices (MPI ranks), a device has banks only for its PEs
 * [group_begin, group_end): what is bound for other PEs all waits in the
 * next pool, contiguous per destination PE in PE order, which is what the
 * rank exchange sends (host/frame/rank_exchange.cpp), and the records it
 * receives lead the next pool.
 *
 * Blocks: each SPMD work-group's outputs are one block, then the pool is cut
 * into blocks of OPSILA_SCATTER_BLOCK entries (num_blocks in all, out_blocks
 * of them outputs).
 *   scatter_count: per block, per-key counts and each entry's rank inside it;
 *   scatter_plan:  per key, a work-group's exclusive scan over the blocks;
 *                  then, in the last work-group, bank capacities that
 *                  follow each PE's demand, bank offsets, the SPMD
 *                  work-groups of the next phase, and the layout of what
 *                  waits;
 *   scatter_move_entries (GPUs) or scatter_move_blocks (CPUs): each record
 *                  to I'(i).
 * A round launches these three: on a GPU each launch waits about 13 us
 * between its enqueue and its start (docs/BENCHMARKS.md). */
#include "lib/descriptor.cl"

/* Where an entry of global rank r with key y goes: its bank slot, or its
 * place in the next pool (scatter_plan's layout, per key). */
typedef struct {
  __global const int *key_begin, *key_count, *key_base;
  __global float4 *banks; /* bank slots: records only (see place) */
  __global float4 *next;
  __global int *next_dest;
} Placement;

/* Entry k of a source vector, of global rank r with key y, to I'(k). */
inline void place(__global const float4 *from, __global const int *from_dest, int k, int y, int r,
                  const Placement *to) {
  int c = to->key_count[y];
  if (r < c) /* a bank's slots all belong to its PE: no key kept there */
    desc_move_record(to->banks, to->key_begin[y] + r, from, k);
  else
    desc_move(to->next, to->next_dest, to->key_base[y] + (r - c), from, from_dest, k);
}

/* One entry of a block walk: entry k of a source vector, whose rank is
 * stored at rank[rank_at]. A valid entry takes the next rank of its key in
 * the block (h[y]++); with `to`, it moves at once to the block's prefix plus
 * that rank (h holds the prefix then); else, with write_rank, the rank (-1
 * for a NIL hole) is stored for the move by entry. */
OPSILA_INLINE void block_entry(__global const float4 *from, __global const int *from_dest, int k, long rank_at,
                               int num_keys, __global int *h, __global int *rank, int write_rank,
                               const Placement *to) {
  int y = from_dest[k];
  bool valid = y >= 0 && y < num_keys;
  if (to) {
    if (valid) place(from, from_dest, k, y, h[y]++, to);
    return;
  }
  int r = valid ? h[y]++ : -1;
  if (write_rank) rank[rank_at] = r;
}

/* The block walk: block b's entries in source order, the records of one
 * SPMD work-group's items or the pool's entries of a pool block, each
 * through block_entry. scatter_count and scatter_move_blocks both walk this
 * way, so the ranks the count gives are the ones the move takes. */
OPSILA_INLINE void walk_block(int b, int pool_len, int out_blocks, int items_per_group, int S, int num_keys,
                              DESC_PARAMS(pool), DESC_PARAMS(out), __global const int *out_item_count,
                              __global int *h, __global int *rank, int write_rank, const Placement *to) {
  if (b >= out_blocks) {
    int first = (b - out_blocks) * OPSILA_SCATTER_BLOCK;
    int end = min(first + OPSILA_SCATTER_BLOCK, pool_len);
    for (int k = first; k < end; ++k)
      block_entry(pool, pool_dest, k, k, num_keys, h, rank, write_rank, to);
    return;
  }
  int first_item = b * items_per_group;
  for (int t = first_item; t < first_item + items_per_group; ++t) {
    int c = out_item_count[t];
    for (int j = 0; j < c; ++j) {
      int at = t * S + j;
      block_entry(out, out_dest, at, (long)pool_len + at, num_keys, h, rank, write_rank, to);
    }
  }
}

/* Counts of block b; hist[b * K + y] = entries with key y (K = num_keys, 2
 * per PE). With write_rank, also each entry's rank inside its block (for the
 * move by entry). Resets scatter_plan's ticket for the launch that follows. */
__kernel void scatter_count(int pool_len, int pool_blocks, int num_blocks, int items_per_group, int S, int num_keys,
                            DESC_PARAMS(pool), DESC_PARAMS(out), __global const int *out_item_count,
                            __global int *hist, __global int *rank, int write_rank, __global int *ticket) {
  int b = get_global_id(0);
  if (b == 0) *ticket = 0;
  if (b >= num_blocks) return;
  __global int *h = hist + (long)b * num_keys;
  for (int y = 0; y < num_keys; ++y) h[y] = 0;
  walk_block(b, pool_len, num_blocks - pool_blocks, items_per_group, S, num_keys, pool, pool_dest, out, out_dest,
             out_item_count, h, rank, write_rank, 0);
}

/* Per key q: hist[b * K + q] becomes the exclusive prefix over blocks,
 * key_total[q] the total (with shared_totals, an atomic write: scatter_plan's
 * last work-group reads the others' totals). A work-group takes keys q = group, group +
 * groups, ...: each work-item sums a run of blocks, the runs' sums are
 * scanned, then each work-item writes its run's prefixes. One work-group
 * per key on a GPU; one in all on a CPU, where work-groups are threads and
 * keys q and q+1 of one block share a cache line (each write would steal it
 * from the other core: 1.3 ms instead of 0.1 ms at 2^20 descriptors). */
inline void scan_keys(int num_blocks, int num_keys, __global int *hist, __global int *key_total, int shared_totals,
                      __local int *sums) {
  int lid = get_local_id(0), lsz = get_local_size(0);
  int run = (num_blocks + lsz - 1) / lsz;
  int begin = min(lid * run, num_blocks), end = min(begin + run, num_blocks);
  for (int q = get_group_id(0); q < num_keys; q += get_num_groups(0)) {
    int s = 0;
    for (int b = begin; b < end; ++b) s += hist[(long)b * num_keys + q];
    sums[lid] = s;
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid == 0) {
      int acc = 0;
      for (int i = 0; i < lsz; ++i) {
        int v = sums[i];
        sums[i] = acc;
        acc += v;
      }
      if (shared_totals)
        atomic_xchg(&key_total[q], acc);
      else
        key_total[q] = acc;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    int acc = sums[lid];
    for (int b = begin; b < end; ++b) {
      long at = (long)b * num_keys + q;
      int v = hist[at];
      hist[at] = acc;
      acc += v;
    }
    barrier(CLK_LOCAL_MEM_FENCE); /* sums is reused by the next key */
  }
}

/* The scan alone: the hit list's (kernels/primary.cl), one key. */
__kernel void scatter_scan(int num_blocks, int num_keys, __global int *hist, __global int *key_total) {
  __local int sums[OPSILA_SCATTER_GROUP_MAX];
  scan_keys(num_blocks, num_keys, hist, key_total, 0, sums);
}

/* Whether this work-group is the launch's last to get here (the ticket
 * starts at 0, scatter_count's doing). A fence orders each group's writes
 * before its ticket, so the last one sees every key total. No group waits
 * for another: any number of them may run at once, or one after another. */
inline bool last_group(__global int *ticket, __local int *last) {
  barrier(CLK_LOCAL_MEM_FENCE | CLK_GLOBAL_MEM_FENCE);
  if (get_local_id(0) == 0) {
    mem_fence(CLK_GLOBAL_MEM_FENCE);
    *last = atomic_inc(ticket) == (int)get_num_groups(0) - 1;
    mem_fence(CLK_GLOBAL_MEM_FENCE);
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  return *last;
}

/* Demand for bank slots on this device: none for PEs of another group;
 * only the records that end their tree (key 2q) while throttled. */
inline int bank_demand(__local const int *key_total, int q, int group_begin, int group_end, int leaves_only) {
  if (q < group_begin || q >= group_end) return 0;
  return key_total[2 * q] + (leaves_only ? 0 : key_total[2 * q + 1]);
}

/* The water level: the largest that fits `slots` (a binary search: the sum
 * is monotonic in it). The whole work-group calls it; partial holds one
 * entry per work-item. */
inline int water_level(int num_pes, int group_begin, int group_end, int slots, int cap, int lv,
                       __local const int *key_total, __local int *partial, __local int *found) {
  int lid = get_local_id(0), lsz = get_local_size(0);
  int lo = 0, hi = slots;
  while (lo < hi) {
    int mid = lo + (hi - lo + 1) / 2;
    long s = 0;
    for (int q = lid; q < num_pes; q += lsz)
      s += min(min(bank_demand(key_total, q, group_begin, group_end, lv), mid), cap);
    partial[lid] = (int)min(s, (long)slots + 1);
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid == 0) {
      long t = 0;
      for (int i = 0; i < lsz; ++i) t += partial[i];
      *found = t <= slots ? 1 : 0;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    if (*found) lo = mid; else hi = mid - 1;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  return lo;
}

/* The scan (scan_keys), then in the launch's last work-group the plan:
 * bank capacity that follows demand, `slots` bank slots this round, split
 * by water-filling. Every PE gets min(demand, level, cap); the level is the
 * largest that fits; slots left over go one each to the PEs still waiting,
 * in PE order. So one hot PE no longer holds every other bank to its share,
 * and a round is full whenever enough descriptors wait. Each bank starts at
 * a multiple of the SPMD work-group size, so no work-group mixes banks.
 * throttle (the host: more wait than the frame's plan holds): demand is the
 * records that end their tree, if this device's PEs have any. Per PE q, key
 * 2q takes the bank's first slots, key 2q + 1 the rest; what waits is laid
 * out per PE in PE order, key 2q first. pe_total[q]: PE q's entries (the
 * rank exchange reads it). counts = {waiting, placed, SPMD work-groups}. */
__kernel void scatter_plan(int num_blocks, int num_keys, __global int *hist, __global int *key_total,
                           __global int *ticket, int num_pes, int group_begin, int group_end, int slots, int cap,
                           int group_size, int throttle, __global int *pe_total, __global int *bank_begin,
                           __global int *bank_count, __global int *key_begin, __global int *key_count,
                           __global int *key_base, __global int *group_pe, __global int *group_first,
                           __global int *counts) {
  __local int partial[OPSILA_SCATTER_GROUP_MAX];
  __local int totals[2 * OPSILA_MAX_PES];
  __local int group_base[OPSILA_MAX_PES];
  __local int flags[2]; /* last work-group, level found */
  __local int leaves_only;
  scan_keys(num_blocks, num_keys, hist, key_total, 1, partial);
  if (!last_group(ticket, &flags[0])) return;
  int lid = get_local_id(0), lsz = get_local_size(0);
  for (int q = lid; q < 2 * num_pes; q += lsz) totals[q] = atomic_add(&key_total[q], 0); /* others' writes */
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid == 0) {
    int leaves = 0;
    for (int q = group_begin; q < group_end && throttle; ++q) leaves |= totals[2 * q];
    leaves_only = throttle && leaves > 0;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  int lv = leaves_only;
  int lo = water_level(num_pes, group_begin, group_end, slots, cap, lv, totals, partial, &flags[1]);
  if (lid == 0) {
    int used = 0;
    for (int q = 0; q < num_pes; ++q) used += min(min(bank_demand(totals, q, group_begin, group_end, lv), lo), cap);
    int spare = slots - used, waiting = 0, placed = 0, begin = 0, groups = 0;
    for (int q = 0; q < num_pes; ++q) {
      int demand = bank_demand(totals, q, group_begin, group_end, lv);
      int c = min(min(demand, lo), cap);
      if (spare > 0 && c < demand && c < cap) {
        ++c;
        --spare;
      }
      int ends = totals[2 * q], more = totals[2 * q + 1];
      int c_ends = min(c, ends);
      bank_count[q] = c;
      bank_begin[q] = begin;
      key_count[2 * q] = c_ends;
      key_begin[2 * q] = begin;
      key_base[2 * q] = waiting;
      key_count[2 * q + 1] = c - c_ends;
      key_begin[2 * q + 1] = begin + c_ends;
      key_base[2 * q + 1] = waiting + (ends - c_ends);
      pe_total[q] = ends + more;
      group_base[q] = groups;
      int g = (c + group_size - 1) / group_size;
      begin += g * group_size;
      groups += g;
      waiting += ends + more - c;
      placed += c;
    }
    counts[0] = waiting;
    counts[1] = placed;
    counts[2] = groups;
  }
  barrier(CLK_LOCAL_MEM_FENCE | CLK_GLOBAL_MEM_FENCE); /* bank_count and bank_begin are read below */
  for (int q = lid; q < num_pes; q += lsz) {
    int g = (bank_count[q] + group_size - 1) / group_size;
    for (int j = 0; j < g; ++j) {
      group_pe[group_base[q] + j] = q;
      group_first[group_base[q] + j] = bank_begin[q] + j * group_size;
    }
  }
}

/* The move by entry, for processors that run many work-items at once (a
 * GPU): one range, a work-item per pool entry, then one per SPMD work-item
 * t (its out_item_count[t] records); each record takes the rank the count
 * stored, after its block's prefix. */
__kernel void scatter_move_entries(int pool_len, int pool_blocks, int num_blocks, int items_per_group, int S,
                                   int num_keys, DESC_PARAMS(pool), DESC_PARAMS(out),
                                   __global const int *out_item_count, __global const int *rank,
                                   __global const int *hist, __global const int *key_begin,
                                   __global const int *key_count, __global const int *key_base, DESC_PARAMS(banks),
                                   DESC_PARAMS(next)) {
  int i = get_global_id(0), out_blocks = num_blocks - pool_blocks;
  Placement to = {key_begin, key_count, key_base, banks, next, next_dest};
  if (i < pool_len) {
    int rk = rank[i];
    if (rk < 0) return;
    int y = pool_dest[i];
    place(pool, pool_dest, i, y, hist[(long)(out_blocks + i / OPSILA_SCATTER_BLOCK) * num_keys + y] + rk, &to);
    return;
  }
  int t = i - pool_len;
  if (t >= out_blocks * items_per_group) return;
  int c = out_item_count[t];
  __global const int *h = hist + (long)(t / items_per_group) * num_keys;
  for (int j = 0; j < c; ++j) {
    int at = t * S + j;
    int rk = rank[pool_len + at];
    if (rk < 0) continue;
    int y = out_dest[at];
    place(out, out_dest, at, y, h[y] + rk, &to);
  }
}

/* The move by block, for processors that run few work-items at a time (a
 * CPU core): one work-item walks a block as scatter_count did and takes each
 * entry's rank from the block's running prefix, so no rank is stored; each
 * core then writes one sequential stream per key. */
__kernel void scatter_move_blocks(int pool_len, int pool_blocks, int num_blocks, int items_per_group, int S,
                                  int num_keys, DESC_PARAMS(pool), DESC_PARAMS(out), __global const int *out_item_count,
                                  __global int *hist, __global const int *key_begin, __global const int *key_count,
                                  __global const int *key_base, DESC_PARAMS(banks), DESC_PARAMS(next)) {
  int b = get_global_id(0);
  if (b >= num_blocks) return;
  Placement to = {key_begin, key_count, key_base, banks, next, next_dest};
  walk_block(b, pool_len, num_blocks - pool_blocks, items_per_group, S, num_keys, pool, pool_dest, out, out_dest,
             out_item_count, hist + (long)b * num_keys, 0, 0, &to);
}
