#!/usr/bin/env python3
"""Plots of an `opsila bench --json` file.

usage: python3 tools/plot_bench.py bench.json -o DIR [--dpi N] [--prefix P]

Writes four PNGs into DIR (names prefixed with P when given):
  scatter.png    scatter speed-up against vector length (the paper's figure 6),
                 and the achieved bandwidth beside the device's copy bandwidth;
  occupancy.png  intersection tests per PE, one panel per tree level, with the
                 level's occupancy (mean/max work over PEs);
  phases.png     where the frame's time goes (kernels by phase, launch
                 overhead), and SPMD / scatter time round by round;
  traffic.png    descriptors sent from PE to PE (scatter), per tree level.
Needs matplotlib (Debian: python3-matplotlib).
"""
import argparse
import json
import math
import os
import sys

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
except ImportError:  # pragma: no cover - depends on the host
    sys.exit("plot_bench.py: matplotlib is missing (Debian: apt-get install python3-matplotlib)")


def length_label(n):
    if n >= 1024 and n & (n - 1) == 0:
        return "2^%d" % (n.bit_length() - 1)
    return str(n)


def title_of(bench):
    scene = os.path.basename(bench["scene"]["path"])
    img = bench["image"]
    dev = bench["device_info"]["name"]
    return "%s, %dx%d, depth %d, %d PEs - %s" % (scene, img["width"], img["height"], bench["depth"], bench["pes"], dev)


def plot_scatter(bench, path, dpi):
    pts = bench["scatter"]
    x = [p["length"] for p in pts]
    by_pes = bench.get("scatter_by_pes") or []
    if by_pes:
        fig = plt.figure(figsize=(8, 9.5))
        gs = fig.add_gridspec(3, 1, height_ratios=[1, 1, 0.7])
        ax1 = fig.add_subplot(gs[0])
        ax2 = fig.add_subplot(gs[1], sharex=ax1)
        ax3 = fig.add_subplot(gs[2])
    else:
        fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 7.5), sharex=True)
    ax1.plot(x, [p["speedup"] for p in pts], "o-", color="C0", label="scatter kernels vs host scatter")
    ax1.axhline(1.0, color="grey", lw=0.8, ls="--")
    ax1.axvline(32767, color="grey", lw=0.8, ls=":")
    ax1.text(32767, 1.0, " 32767 (the paper's longest)", fontsize=8, color="grey", va="bottom")
    ax1.set_xscale("log", base=2)
    ax1.set_ylabel("speed-up (host time / kernel time)")
    ax1.set_title("Scatter speed-up against vector length (cf. figure 6)", fontsize=11)
    ax1.grid(True, which="major", alpha=0.3)
    ax1.legend(fontsize=8, loc="upper left")

    ax2.plot(x, [p["gbytes_per_s"] for p in pts], "o-", color="C0", label="scatter kernels")
    ax2.plot(x, [p["host_gbytes_per_s"] for p in pts], "s--", color="C2", ms=4, label="host scatter (1 thread)")
    ax2.plot(x, [p["copy_kernel_gbytes_per_s"] for p in pts], "^-", color="C3", ms=4, label="copy kernel (ceiling)")
    ax2.plot(x, [p["copy_buffer_gbytes_per_s"] for p in pts], "v:", color="C1", ms=4, label="clEnqueueCopyBuffer")
    ax2.set_xscale("log", base=2)
    ax2.set_yscale("log")
    ax2.set_xlabel("vector length (descriptors)")
    ax2.set_ylabel("GB/s (descriptor bytes read + written)")
    ax2.grid(True, which="major", alpha=0.3)
    ax2.legend(fontsize=8, loc="lower right")
    ticks = [n for n in x if n & (n - 1) == 0 and int(math.log2(n)) % 2 == 0]
    ax2.set_xticks(ticks)
    ax2.set_xticklabels([length_label(n) for n in ticks], fontsize=8)
    if by_pes:
        xs = range(len(by_pes))
        ax3.bar([i - 0.2 for i in xs], [p["gbytes_per_s"] for p in by_pes], 0.4, color="C0", label="scatter kernels")
        ax3.bar([i + 0.2 for i in xs], [p["copy_kernel_gbytes_per_s"] for p in by_pes], 0.4, color="C3",
                label="copy kernel")
        for i, p in enumerate(by_pes):
            ax3.text(i - 0.2, p["gbytes_per_s"], "%.0f%%" % (100 * p["fraction_of_copy"]), ha="center",
                     va="bottom", fontsize=8)
        ax3.set_xticks(list(xs))
        ax3.set_xticklabels([str(p["pes"]) for p in by_pes])
        ax3.set_xlabel("PEs (destination banks) at %s descriptors" % length_label(by_pes[0]["length"]))
        ax3.set_ylabel("GB/s")
        ax3.legend(fontsize=8)
        ax3.grid(True, axis="y", alpha=0.3)
    fig.suptitle(title_of(bench), fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def plot_occupancy(bench, path, dpi):
    r = bench["render"]
    levels = [lv for lv in r["levels"] if lv["descriptors"] > 0]
    pes = r["pe"]
    n = max(1, len(levels))
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.6 * n + 1.2), sharex=True, squeeze=False)
    for ax, lv in zip(axes[:, 0], levels):
        l = lv["level"]
        tests = [p["tests_by_level"][l] for p in pes]
        desc = [p["descriptors_by_level"][l] for p in pes]
        m = max(tests) or 1
        ax.bar(range(len(pes)), [t / m for t in tests], color="C0", alpha=0.85, label="intersection tests")
        md = max(desc) or 1
        ax.plot(range(len(pes)), [d / md for d in desc], "k.", ms=5, label="descriptors")
        mean = sum(tests) / len(tests) / m
        ax.axhline(mean, color="C3", lw=1, ls="--")
        occ = lv["occupancy"]
        ax.set_ylabel("level %d" % l, fontsize=9)
        ax.set_ylim(0, 1.08)
        label = "occupancy %.2f (tests), %.2f (descriptors)" % (occ or 0, lv["occupancy_descriptors"] or 0)
        ax.text(0.995, 0.93, label, transform=ax.transAxes, ha="right", va="top", fontsize=8,
                bbox=dict(facecolor="white", alpha=0.8, lw=0))
    axes[0, 0].legend(fontsize=7, loc="upper left")
    axes[-1, 0].set_xlabel("PE")
    axes[-1, 0].set_xticks(range(len(pes)))
    axes[-1, 0].tick_params(axis="x", labelsize=7)
    fig.suptitle("Work per PE, relative to the busiest PE (dashed: mean); overall occupancy %.2f\n%s"
                 % (r["occupancy"] or 0, title_of(bench)), fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def plot_phases(bench, path, dpi):
    r = bench["render"]
    tk = r["time_by_kernel"]
    groups = [
        ("item buffer (SIMD)", ["item_buffer"], "C1"),
        ("primary descriptors (SIMD)", ["count_hits", "hit_list_scan", "list_hits", "build_primary"], "C4"),
        ("SPMD phases", ["spmd_phase"], "C0"),
        ("scatter (SIMD exchange)", ["scatter_count", "scatter_plan", "scatter_move"], "C3"),
    ]
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(9, 7), gridspec_kw={"height_ratios": [1, 2.2]})
    left = 0.0
    total = r["seconds"] if r["seconds"] > 0 else 1.0
    for name, kernels, color in groups:
        s = sum(tk[k]["seconds"] for k in kernels if k in tk)
        ax1.barh(0, s, left=left, color=color, label="%s %.1f%%" % (name, 100 * s / total))
        left += s
    over = r["overhead_seconds"]
    ax1.barh(0, over, left=left, color="0.6", hatch="//", label="launch overhead %.1f%%" % (100 * over / total))
    ax1.set_yticks([])
    ax1.set_xlabel("seconds (median frame %.3f s, %d rounds = %d phase switches)"
                   % (r["seconds"], r["rounds"], r["phase_switches"]))
    ax1.legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.45))
    ax1.set_title("Time of one frame by phase", fontsize=10)

    rounds = {}
    for p in r["phases"]:
        if p["round"] < 0:
            continue
        e = rounds.setdefault(p["round"], {"spmd": 0.0, "scatter": 0.0, "other": 0.0})
        if p["name"] == "spmd_phase":
            e["spmd"] += p["seconds"]
        elif p["name"].startswith("scatter_"):
            e["scatter"] += p["seconds"]
        else:
            e["other"] += p["seconds"]
    xs = sorted(rounds)
    if xs:
        spmd = [1e3 * rounds[i]["spmd"] for i in xs]
        sc = [1e3 * rounds[i]["scatter"] for i in xs]
        ot = [1e3 * rounds[i]["other"] for i in xs]
        ax2.stackplot(xs, spmd, sc, ot, colors=["C0", "C3", "C4"], labels=["SPMD phase", "scatter", "build primary"],
                      alpha=0.9, lw=0)
        ax2.set_xlim(xs[0], xs[-1])
    ax2.set_xlabel("round (one SPMD phase + one scatter)")
    ax2.set_ylabel("ms (OpenCL-profiled)")
    ax2.set_title("Kernel time per round", fontsize=10)
    ax2.legend(fontsize=8, loc="upper right")
    ax2.grid(True, alpha=0.3)
    fig.suptitle(title_of(bench), fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def plot_traffic(bench, path, dpi):
    traffic = bench["render"]["traffic"]
    mats = [(l, m) for l, m in enumerate(traffic) if any(any(v for v in row) for row in m)]
    if not mats:
        fig, ax = plt.subplots(figsize=(5, 2))
        ax.text(0.5, 0.5, "no traffic recorded (more than 64 PEs, or no descriptors moved)", ha="center")
        ax.axis("off")
        fig.savefig(path, dpi=dpi)
        plt.close(fig)
        return
    n = len(mats)
    cols = min(3, n)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols + 0.8, 3.4 * rows + 0.6), squeeze=False)
    vmax = max(max(max(row) for row in m) for _, m in mats)
    im = None
    for k, (l, m) in enumerate(mats):
        ax = axes[k // cols][k % cols]
        data = [[v if v > 0 else float("nan") for v in row] for row in m]
        im = ax.imshow(data, cmap="viridis", norm=LogNorm(vmin=1, vmax=max(vmax, 2)), interpolation="nearest")
        total = sum(sum(row) for row in m)
        diag = sum(m[i][i] for i in range(len(m)))
        ax.set_title("level %d: %d descriptors, %.0f%% stay" % (l, total, 100.0 * diag / max(total, 1)), fontsize=8)
        ax.set_xlabel("destination PE", fontsize=8)
        ax.set_ylabel("source PE", fontsize=8)
        ax.tick_params(labelsize=6)
    for k in range(n, rows * cols):
        axes[k // cols][k % cols].axis("off")
    fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.8, label="descriptors (log)")
    fig.suptitle("PE-to-PE descriptor traffic (scatter)\n" + title_of(bench), fontsize=9)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description="Plots of an `opsila bench --json` file.")
    ap.add_argument("json", help="bench JSON (opsila bench ... --json FILE)")
    ap.add_argument("-o", "--output", required=True, help="folder for the PNGs (created if missing)")
    ap.add_argument("--dpi", type=int, default=90)
    ap.add_argument("--prefix", default="", help="prefix of the PNG names (e.g. bench_)")
    a = ap.parse_args()
    try:
        with open(a.json) as f:
            bench = json.load(f)
    except (OSError, ValueError) as e:
        sys.exit("plot_bench.py: %s: %s" % (a.json, e))
    for key in ("scatter", "render", "device_info"):
        if key not in bench:
            sys.exit("plot_bench.py: %s: not an opsila bench JSON (no '%s')" % (a.json, key))
    os.makedirs(a.output, exist_ok=True)
    out = {
        "scatter.png": plot_scatter,
        "occupancy.png": plot_occupancy,
        "phases.png": plot_phases,
        "traffic.png": plot_traffic,
    }
    for name, fn in out.items():
        p = os.path.join(a.output, a.prefix + name)
        fn(bench, p, a.dpi)
        print("wrote %s (%d KB)" % (p, (os.path.getsize(p) + 1023) // 1024))


if __name__ == "__main__":
    main()
