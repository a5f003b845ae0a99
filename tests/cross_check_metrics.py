#!/usr/bin/env python3
"""Independent cross-check of `gi compare` against public implementations.

SSIM is checked against scikit-image's structural_similarity(gaussian_weights=True, sigma=1.5,
use_sample_covariance=False, data_range=1), per channel then averaged; mean LDR-FLIP against
NVIDIA's flip_evaluator package (LDR mode, default 67.02 ppd). Both must agree within 1e-3
(docs/METRICS.md). `grade255` (ten Brug's grade on an SSIM with data_range=255 over [0, 1] values,
black-in-both pixels left out) is recomputed from scikit-image's SSIM maps; its per-channel MSSIM
must agree within 1e-6. The magma FLIP heat map must match flip_evaluator's colours on at least 99% of
pixels, within 4/255 everywhere (values on an index boundary may round to the next entry). Image pairs (noise, blur, colour shift, ...) are generated with numpy from a
fixed seed and stored as 8-bit PNGs, so both sides read exactly the same values.

Usage: cross_check_metrics.py GI_BINARY [WORK_DIR]
(WORK_DIR keeps the images, JSON, heat maps, and pydeps/ when pip had to install with --target.)
Exit status: 0 agreement, 1 disagreement or failure, 77 the Python packages cannot be had
(ctest SKIP_RETURN_CODE).
"""
import importlib
import json
import os
import subprocess
import sys
import tempfile

TOLERANCE = 1e-3
# grade255's per-channel MSSIM (SSIM with data_range=255 on [0, 1] values) sits within ~1e-3 of 1,
# and the grade multiplies its error by ~1e4 (d(10 m^1000)/dm), so it is held much closer.
GRADE255_MSSIM_TOLERANCE = 1e-6
PACKAGES = ["numpy", "imageio", "scikit-image", "flip-evaluator"]


def import_or_install(deps_dir):
    """Imports numpy, imageio, skimage, flip_evaluator, pip-installing them if missing: first into
    the running Python; where that is refused (Debian's externally-managed system Python), into
    deps_dir with --target, which later runs find again without reinstalling."""
    names = ["numpy", "imageio.v2", "skimage.metrics", "flip_evaluator"]
    if os.path.isdir(deps_dir):
        sys.path.insert(0, deps_dir)
    try:
        return [importlib.import_module(n) for n in names]
    except ImportError as first:
        print(f"cross-check: {first}; installing {' '.join(PACKAGES)} with pip", flush=True)
    pip = [sys.executable, "-m", "pip", "install", "--quiet", "--disable-pip-version-check"]
    log = ""
    for cmd in (pip + PACKAGES, pip + ["--target", deps_dir] + PACKAGES):
        r = subprocess.run(cmd, capture_output=True, text=True)
        log += f"$ {' '.join(cmd)}\n{r.stdout}{r.stderr}"
        if r.returncode == 0:
            break
    else:
        print(log + "cross-check: SKIP: pip could not install the packages", flush=True)
        sys.exit(77)
    if deps_dir not in sys.path:
        sys.path.insert(0, deps_dir)
    importlib.invalidate_caches()
    try:
        return [importlib.import_module(n) for n in names]
    except ImportError as e:
        print(log + f"cross-check: SKIP: still cannot import after pip install: {e}", flush=True)
        sys.exit(77)


def make_pairs(np):
    """(name, reference, test) float images in [0,1], quantized to 8 bits."""
    rng = np.random.default_rng(20240611)

    def base(h, w):
        y, x = np.mgrid[0:h, 0:w].astype(np.float64)
        img = np.zeros((h, w, 3))
        img[..., 0] = 0.5 + 0.4 * np.sin(x / 9.0) * np.cos(y / 13.0)
        img[..., 1] = np.clip(x / w * 0.8 + 0.1 * np.sin((x + y) / 5.0), 0, 1)
        img[..., 2] = 0.3 + 0.3 * ((x // 16 + y // 16) % 2)  # checkerboard: edges for FLIP
        disk = (x - w * 0.6) ** 2 + (y - h * 0.4) ** 2 < (min(h, w) * 0.2) ** 2
        img[disk] = [0.9, 0.2, 0.1]
        img[: h // 6, : w // 5] = 0.0  # a black corner (grade ignores black-in-both pixels)
        img += rng.normal(0, 0.01, img.shape)  # fine texture
        return np.clip(img, 0, 1)

    def blur(img, radius):
        # Separable box blur, repeated twice (≈ Gaussian), edge-padded.
        out = img
        for _ in range(2):
            for axis in (0, 1):
                pad = [(0, 0)] * 3
                pad[axis] = (radius, radius)
                p = np.pad(out, pad, mode="edge")
                c = np.cumsum(p, axis=axis)
                c = np.concatenate([np.zeros_like(np.take(c, [0], axis=axis)), c], axis=axis)
                n = out.shape[axis]
                out = (np.take(c, range(2 * radius + 1, 2 * radius + 1 + n), axis=axis) -
                       np.take(c, range(0, n), axis=axis)) / (2 * radius + 1)
        return out

    q = lambda a: np.round(np.clip(a, 0, 1) * 255.0) / 255.0
    pairs = []
    a = base(192, 256)
    pairs.append(("noise_0.03", q(a), q(a + rng.normal(0, 0.03, a.shape))))
    pairs.append(("noise_0.15", q(a), q(a + rng.normal(0, 0.15, a.shape))))
    pairs.append(("blur_r2", q(a), q(blur(a, 2))))
    pairs.append(("colour_shift", q(a), q(a * np.array([1.08, 0.95, 0.85]) + np.array([0.02, 0.0, 0.03]))))
    b = base(97, 173)  # odd size, not a multiple of anything
    pairs.append(("odd_size_mix", q(b), q(blur(b, 1) * 0.9 + rng.normal(0, 0.05, b.shape))))
    pairs.append(("identical", q(b), q(b)))
    return pairs


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 1
    gi = os.path.abspath(sys.argv[1])
    work = os.path.abspath(sys.argv[2]) if len(sys.argv) > 2 else tempfile.mkdtemp(prefix="gi_cross_check_")
    os.makedirs(work, exist_ok=True)
    np, imageio, skm, flip_evaluator = import_or_install(os.path.join(work, "pydeps"))

    failures = 0
    worst_ssim = worst_flip = worst_grade = 0.0
    print(f"{'pair':<14} {'ssim gi':>10} {'ssim skimage':>12} {'diff':>9}   {'flip gi':>9} {'flip ref':>9} {'diff':>9}")
    for name, ref, test in make_pairs(np):
        rp, tp, jp = (os.path.join(work, f"{name}_{s}") for s in ("ref.png", "test.png", "metrics.json"))
        imageio.imwrite(rp, (ref * 255.0 + 0.5).astype(np.uint8))
        imageio.imwrite(tp, (test * 255.0 + 0.5).astype(np.uint8))
        hp = os.path.join(work, f"{name}_flip.png")
        r = subprocess.run([gi, "compare", "--reference", rp, "--test", tp, "--metrics", "ssim,grade255,flip", "--json", jp,
                            "--heatmap", hp],
                           capture_output=True, text=True)
        if r.returncode != 0:
            print(f"{name}: gi compare failed ({r.returncode}): {r.stdout}{r.stderr}")
            failures += 1
            continue
        with open(jp) as f:
            doc = json.load(f)
        got, got_details = doc["metrics"], doc["details"]

        # Read back what gi read, so both sides see identical 8-bit values.
        ref8 = imageio.imread(rp).astype(np.float64) / 255.0
        test8 = imageio.imread(tp).astype(np.float64) / 255.0
        ssim_ref = float(np.mean([
            skm.structural_similarity(ref8[..., c], test8[..., c], gaussian_weights=True, sigma=1.5,
                                      use_sample_covariance=False, data_range=1.0) for c in range(3)]))
        # grade255: per-channel SSIM maps with data_range=255 on the [0, 1] values, the 5-pixel border
        # cropped, pixels black (below half an 8-bit level) in both images left out, 10 x mean MSSIM^1000.
        interior = (slice(5, -5), slice(5, -5))
        black = np.all(ref8[interior] < 0.5 / 255.0, axis=-1) & np.all(test8[interior] < 0.5 / 255.0, axis=-1)
        mssim255 = []
        for c in range(3):
            _, smap = skm.structural_similarity(ref8[..., c], test8[..., c], gaussian_weights=True, sigma=1.5,
                                                use_sample_covariance=False, data_range=255.0, full=True)
            mssim255.append(float(np.mean(smap[interior][~black])))
        grade255_ref = 10.0 * float(np.mean(np.clip(mssim255, 0.0, 1.0) ** 1000))
        dg = max(abs(a - b) for a, b in zip(got_details["grade255_mssim_rgb"], mssim255))
        worst_grade = max(worst_grade, dg)
        magma_ref, flip_ref, _ = flip_evaluator.evaluate(ref8.astype(np.float32), test8.astype(np.float32), "LDR")
        # Heat maps: gi's magma PNG against flip_evaluator's magma map, both as 8-bit colours.
        heat_gi = imageio.imread(hp)[..., :3].astype(np.int32)
        heat_ref = np.round(np.clip(magma_ref, 0, 1) * 255.0).astype(np.int32)
        heat_off = float(np.mean(np.any(heat_gi != heat_ref, axis=-1)))
        heat_max = int(np.max(np.abs(heat_gi - heat_ref)))
        ds, df = abs(got["ssim"] - ssim_ref), abs(got["flip"] - float(flip_ref))
        worst_ssim, worst_flip = max(worst_ssim, ds), max(worst_flip, df)
        # Error values on a magma index boundary may round to the neighbouring entry (≤ 2/255 apart).
        bad = (ds > TOLERANCE or df > TOLERANCE or heat_off > 0.01 or heat_max > 4 or dg > GRADE255_MSSIM_TOLERANCE
               or abs(got["grade255"] - grade255_ref) > 1e4 * GRADE255_MSSIM_TOLERANCE)
        failures += bad
        print(f"{name:<14} {got['ssim']:>10.6f} {ssim_ref:>12.6f} {ds:>9.2e}   {got['flip']:>9.6f} {float(flip_ref):>9.6f} "
              f"{df:>9.2e}   heat map: {heat_off:.3%} px differ, max {heat_max}/255{'  FAIL' if bad else ''}")

    print(f"max |diff|: ssim {worst_ssim:.2e}, flip {worst_flip:.2e} (tolerance {TOLERANCE:g}), "
          f"grade255 MSSIM {worst_grade:.2e} (tolerance {GRADE255_MSSIM_TOLERANCE:g})")
    print("cross-check: " + (f"FAILED ({failures} pair(s))" if failures else "all pairs agree"))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
