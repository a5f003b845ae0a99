#!/usr/bin/env python3
"""Markdown tables from a `gi sweep` folder (finished or not), for docs/results/.

Reads DIR/runs/*/result.json (what the sweep writes per configuration as it goes), so it also
summarizes a sweep that is still running or was interrupted. One table per scene and resolution:
technique, the parameters the spec set, device ms per frame (sum of kernels, median), the
technique's own passes (kernels not named "shadow maps"/"gbuffer"/"direct"), frame wall ms,
device memory, the quality metrics against the sweep's reference (and its spp), and the
statistics a technique reports about its last frame (e.g. second-order's re-shaded share).

Usage: bench/sweep_markdown.py DIR [--spec-params-only]
"""
import glob
import json
import os
import sys

FOUNDATION = ("shadow maps", "gbuffer", "direct lighting", "rsm: setup", "rsm: binning", "rsm: tiles", "rsm: resolve")


def load(dir_):
    rows = []
    for f in sorted(glob.glob(os.path.join(dir_, "runs", "*", "result.json"))):
        with open(f) as fh:
            r = json.load(fh)
        rows.append(r)
    rows.sort(key=lambda r: r["configuration"]["index"])
    return rows


def fmt(v, digits=1):
    return "—" if v is None else f"{v:.{digits}f}"


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    dir_ = sys.argv[1]
    rows = load(dir_)
    groups = {}
    for r in rows:
        c = r["configuration"]
        groups.setdefault((c["scene_label"], c["width"], c["height"]), []).append(r)
    for (scene, w, h), rs in groups.items():
        print(f"\n### {scene}, {w}×{h}\n")
        spps = sorted({(r.get("bench", {}).get("quality") or {}).get("reference_spp") for r in rs} - {None})
        if spps:
            print(f"Reference: {', '.join(str(s) for s in spps)} spp.\n")
        stats = []
        for r in rs:
            for k in r.get("bench", {}).get("statistics", {}):
                if k not in stats:
                    stats.append(k)
        extra = "".join(f" {k} |" for k in stats)
        print("| technique | parameters | device ms / frame | technique passes ms | frame wall ms | device MB | SSIM | FLIP | relMSE |" + extra)
        print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |" + " ---: |" * len(stats))
        for r in rs:
            c = r["configuration"]
            params = " ".join(f"{k}={v}" for k, v in c["params"].items()) or "—"
            if r["status"] != "ok" or "bench" not in r:
                print(f"| {c['technique']} | {params} | failed: {r.get('message', '')[:80]} | | | | | | |" + " |" * len(stats))
                continue
            b = r["bench"]
            own = sum(k["median_ms"] for k in b["kernels"] if not k["name"].startswith(FOUNDATION))
            q = b.get("quality") or {}
            print(f"| {c['technique']} | {params} | {fmt(b['device_total_ms']['median_ms'])} | {fmt(own)} | "
                  f"{fmt(b['frame_wall_ms']['median_ms'])} | {fmt(b.get('device_bytes', 0) / 1e6)} | "
                  f"{fmt(q.get('ssim'), 4)} | {fmt(q.get('flip'), 4)} | {fmt(q.get('relmse'), 4)} |"
                  + "".join(f" {b['statistics'][k]:.4g} |" if k in b.get("statistics", {}) else " — |" for k in stats))
    print(f"\n{len(rows)} configuration(s) finished.")


if __name__ == "__main__":
    main()
