#!/usr/bin/env python3
"""Plots of seed 000's interleaving experiment from interleaving_bench's markdown output.

    build/interleaving_bench --size 256 --spp 512 --frames 5 > run.md
    bench/interleaving_plot.py run.md docs/results/

writes interleaving_time.png (time per configuration against N, log scale, with the thesis's RSM
gather times for comparison of the trend), interleaving_error.png (SSD against the un-interleaved
image, the thesis's measure) and interleaving_reference.png (SSIM against the path-traced
reference). Needs matplotlib (pip install matplotlib).
"""
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# Seed 000 §5 (seconds per frame, GeForce GT 525M): RSM gather by pattern and N.
THESIS_RSM_MS = {
    "1x1": {64: 125.8, 256: 507.3, 1024: 1958.3},
    "2x4": {64: 84.6, 256: 159.8, 1024: 536.7},
    "4x4": {64: 51.9, 256: 117.0, 1024: 344.0},
    "8x8": {64: 55.5, 256: 73.8, 1024: 151.7},
}


def read_rows(path):
    rows = []
    with open(path) as f:
        for line in f:
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cells) != 8 or not cells[1].isdigit():
                continue
            tech, n, pattern, ms, _, ssd, ssim, relmse = cells
            rows.append(dict(tech=tech, n=int(n), pattern=pattern, ms=float(ms), ssd=float(ssd),
                             ssim=float(ssim), relmse=float(relmse)))
    if not rows:
        sys.exit(f"error: no result rows in {path} (expected interleaving_bench's markdown table)")
    return rows


def series(rows, keep):
    out = defaultdict(list)
    for r in rows:
        label = keep(r)
        if label:
            out[label].append((r["n"], r))
    return {k: sorted(v, key=lambda t: t[0]) for k, v in out.items()}


def gather_label(r):
    if r["tech"] == "gather (vpl)":
        return "gather 1x1 (vpl)"
    if r["tech"] == "gather (igi)":
        return f"gather {r['pattern']} box filter"
    if r["tech"] == "gather (igi, separable filter)":
        return f"gather {r['pattern']} separable filter"
    return None


def splat_label(r):
    if r["tech"].startswith("splat eps=1e-4 ") and "[vs splat 1x1]" in r["tech"]:
        order = r["tech"].split()[2]
        return f"splat {r['pattern']} {order}"
    return None


PATTERN_COLOURS = {"1x1": "black", "2x2": "tab:blue", "2x4": "tab:orange", "4x4": "tab:green", "8x8": "tab:red"}


def plot(ax, data, key, style_of):
    for label, pts in data.items():
        colour = next((c for p, c in PATTERN_COLOURS.items() if p in label), None)
        ax.plot([n for n, _ in pts], [r[key] for _, r in pts], style_of(label), label=label, markersize=4,
                color=colour)
    ax.set_xscale("log", base=2)
    ax.set_xlabel("VPLs per light (N)")
    ax.grid(True, which="both", alpha=0.3)


def style(label):
    return ("--" if "separable" in label or "contiguous" in label else "-") + ("s" if "1x1" in label else "o")


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: interleaving_plot.py RUN.md OUT_DIR")
    rows, out = read_rows(sys.argv[1]), sys.argv[2].rstrip("/")
    gather = series(rows, gather_label)
    splat = series(rows, splat_label)

    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    plot(ax[0], gather, "ms", style)
    ax[0].set_yscale("log")
    ax[0].set_ylabel("ms per frame (VPL generation .. filter)")
    ax[0].set_title("This engine (PoCL, 2-core EPYC)")
    ax[0].legend(fontsize=7)
    for pattern, pts in THESIS_RSM_MS.items():
        ax[1].plot(list(pts), list(pts.values()), "-o", label=f"RSM gather {pattern}", markersize=4,
                   color=PATTERN_COLOURS[pattern])
    ax[1].set_xscale("log", base=2)
    ax[1].set_yscale("log")
    ax[1].set_xlabel("VPLs per light (N)")
    ax[1].set_title("Seed 000 (GT 525M, Direct3D 10)")
    ax[1].grid(True, which="both", alpha=0.3)
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(f"{out}/interleaving_time.png", dpi=110)

    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    plot(ax[0], {k: v for k, v in gather.items() if "1x1" not in k}, "ssd", style)
    ax[0].set_ylabel("SSD of intensity vs un-interleaved")
    ax[0].set_title("Gather vs vpl at the same N")
    ax[0].legend(fontsize=7)
    plot(ax[1], splat, "ssd", style)
    ax[1].set_title("Interleaved splat vs un-interleaved splat (eps = 1e-4)")
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(f"{out}/interleaving_error.png", dpi=110)

    fig, ax = plt.subplots(figsize=(6, 4.2))
    plot(ax, gather, "ssim", style)
    ax.set_ylabel("SSIM vs path-traced one-bounce reference")
    ax.set_title("Gather against the reference")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(f"{out}/interleaving_reference.png", dpi=110)


if __name__ == "__main__":
    main()
