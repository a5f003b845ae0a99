#!/usr/bin/env python3
"""Independent cross-check of the reference path tracer against Mitsuba 3.

What it does: exports the built-in Cornell box with the hidden `gi export-scene` (one OBJ per
instance + scene.json with materials and the camera), renders it with Mitsuba 3 (`scalar_rgb`
variant: RGB radiance, no spectral upsampling; `path` integrator; box pixel filter; area emitters
on the emissive instances; `diffuse` BSDFs with the base colours) and with `gi reference
--diffuse-only`, and compares the mean radiance per wall / block over pixels whose whole 3x3
neighbourhood sees that instance (instance masks from Mitsuba ray casts through our camera's pixel
centres, so both images are masked the same way).

Why --diffuse-only: our glTF materials carry a GGX lobe with F0 = 0.04 on top of Lambert (the
engine's one BRDF, brdf.h); Mitsuba has no identical BSDF, so the comparison is made with the
purely Lambertian variant, which both renderers define the same way (f = rho/pi).

Bounce counts: Mitsuba's max_depth counts path segments (1 = emitters seen directly), ours the
reflections (0 = emitters seen directly), so max_depth = max_bounces + 1.

Pass criterion: every instance with >= 50 interior pixels within --tolerance (default 2 %) in
each channel whose value is above 1 % of the image's maximum channel mean. Prints a table;
exit status 1 on failure.

Usage: python3 bench/cross_check_mitsuba.py --gi build-ref/gi [--size 128] [--spp 1024]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile


def ensure_mitsuba():
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        subprocess.check_call([sys.executable, "-m", "pip", "install", "--quiet", "mitsuba"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--gi", default="build/gi", help="the gi binary")
    ap.add_argument("--scene", default="", help="scene spec for gi (default: built-in Cornell box)")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--max-bounces", type=int, default=8)
    ap.add_argument("--tolerance", type=float, default=0.02)
    ap.add_argument("--work", default="", help="folder for intermediate files (default: a temp dir)")
    args = ap.parse_args()

    ensure_mitsuba()
    import mitsuba as mi
    import numpy as np
    mi.set_variant("scalar_rgb")

    work = args.work or tempfile.mkdtemp(prefix="gi_mitsuba_")
    os.makedirs(work, exist_ok=True)
    export = os.path.join(work, "export")
    scene_args = [args.scene] if args.scene else []
    subprocess.check_call([args.gi, "export-scene", *scene_args, "--out", export])
    with open(os.path.join(export, "scene.json")) as f:
        desc = json.load(f)
    cam = desc["cameras"][0]
    W = H = args.size

    # ---- Mitsuba scene -------------------------------------------------------------------------
    d = {"type": "scene",
         "integrator": {"type": "path", "max_depth": args.max_bounces + 1},
         "sensor": {"type": "perspective", "fov_axis": "y", "fov": math.degrees(cam["yfov"]),
                    "near_clip": 0.001, "far_clip": 100.0,
                    "to_world": mi.ScalarTransform4f().look_at(origin=cam["position"], target=cam["target"],
                                                               up=cam["up"]),
                    "sampler": {"type": "independent", "sample_count": args.spp},
                    "film": {"type": "hdrfilm", "width": W, "height": H, "rfilter": {"type": "box"},
                             "pixel_format": "rgb"}}}
    names = []
    for inst in desc["instances"]:
        m = desc["materials"][inst["material"]]
        if m["textured"] or m["metallic"] > 0:
            print(f"warning: instance {inst['id']} has a textured/metallic material; compared by its factors")
        shape = {"type": "obj", "filename": os.path.join(export, inst["file"]), "face_normals": True,
                 "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": m["base_color"][:3]}}}
        if max(m["emissive"]) > 0:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": m["emissive"]}}
        name = f"instance_{inst['id']}"
        d[name] = shape
        names.append(name)
    scene = mi.load_dict(d)
    mts_img = np.array(mi.render(scene, spp=args.spp))[:, :, :3]
    mi.Bitmap(mts_img).write(os.path.join(work, "mitsuba.exr"))

    # ---- ours ----------------------------------------------------------------------------------
    ours_path = os.path.join(work, "ours.exr")
    subprocess.check_call([args.gi, "reference", *scene_args, "--width", str(W), "--height", str(H),
                           "--spp", str(args.spp), "--max-bounces", str(args.max_bounces), "--diffuse-only",
                           "--out", ours_path])
    ours = np.array(mi.Bitmap(ours_path))[:, :, :3]

    # ---- instance masks through OUR camera convention (views.h) --------------------------------
    pos, tgt, up = (np.array(cam[k], dtype=float) for k in ("position", "target", "up"))
    fwd = (tgt - pos) / np.linalg.norm(tgt - pos)
    right = np.cross(fwd, up); right /= np.linalg.norm(right)
    upv = np.cross(right, fwd)
    th = math.tan(0.5 * cam["yfov"])
    aspect = W / H
    # Masks come from a second scene of bare shapes: Mitsuba merges meshes that share a BSDF
    # configuration into one shape (all white walls and blocks), which would hide the instances.
    mask_scene = mi.load_dict({"type": "scene", **{
        f"instance_{inst['id']}": {"type": "obj", "filename": os.path.join(export, inst["file"])}
        for inst in desc["instances"]}})
    labels = sorted(names)
    shape_index = {name: i for i, name in enumerate(labels)}
    ids = np.full((H, W), -1, dtype=int)
    for py in range(H):
        for px in range(W):
            nx = (px + 0.5) / W * 2 - 1
            ny = 1 - (py + 0.5) / H * 2
            dirv = fwd + nx * th * aspect * right + ny * th * upv
            dirv /= np.linalg.norm(dirv)
            si = mask_scene.ray_intersect(mi.Ray3f(mi.Point3f(*pos), mi.Vector3f(*dirv)))
            if si.is_valid():
                ids[py, px] = shape_index.get(si.shape.id(), -2)
    interior = np.zeros_like(ids, dtype=bool)
    interior[1:-1, 1:-1] = True
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            interior[1:-1, 1:-1] &= ids[1:-1, 1:-1] == ids[1 + dy:H - 1 + dy, 1 + dx:W - 1 + dx]

    # Orientation check: the image halves must agree (catches a mirrored camera convention).
    lm, rm = ours[:, : W // 3].mean(axis=(0, 1)), ours[:, -W // 3:].mean(axis=(0, 1))
    lt, rt = mts_img[:, : W // 3].mean(axis=(0, 1)), mts_img[:, -W // 3:].mean(axis=(0, 1))
    if np.sign(lm[0] - rm[0]) != np.sign(lt[0] - rt[0]):
        print("FAIL: the two images are mirrored (camera conventions differ)")
        return 1

    peak = max(ours.reshape(-1, 3).mean(axis=0).max(), 1e-12)
    ok = True
    print(f"{'instance':<14}{'pixels':>7}  {'ours (R G B)':>30}  {'Mitsuba (R G B)':>30}  {'rel. diff %':>22}")
    for i in sorted(set(ids[interior].tolist())):
        if i < 0:
            continue
        mask = interior & (ids == i)
        n = int(mask.sum())
        if n < 50:
            continue
        a = ours[mask].mean(axis=0)
        b = mts_img[mask].mean(axis=0)
        rel = (a - b) / np.maximum(b, 1e-12)
        checked = [c for c in range(3) if b[c] > 0.01 * peak]
        bad = any(abs(rel[c]) > args.tolerance for c in checked)
        ok &= not bad
        fmt = lambda v: " ".join(f"{x:9.5f}" for x in v)
        print(f"{labels[i]:<14}{n:>7}  {fmt(a):>30}  {fmt(b):>30}  {' '.join(f'{100 * x:+6.2f}' for x in rel):>22}"
              f"{'  FAIL' if bad else ''}")
    whole_a, whole_b = ours.mean(axis=(0, 1)), mts_img.mean(axis=(0, 1))
    print(f"{'whole image':<14}{W * H:>7}  {' '.join(f'{x:9.5f}' for x in whole_a):>30}  "
          f"{' '.join(f'{x:9.5f}' for x in whole_b):>30}  "
          f"{' '.join(f'{100 * x:+6.2f}' for x in (whole_a - whole_b) / np.maximum(whole_b, 1e-12)):>22}")
    print(("PASS" if ok else "FAIL") + f": per-instance means within {100 * args.tolerance:.1f} % "
          f"({W}x{H}, {args.spp} spp, max {args.max_bounces} bounces); images in {work}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
