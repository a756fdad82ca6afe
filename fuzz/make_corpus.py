#!/usr/bin/env python3
"""Regenerates the seed corpora in fuzz/corpus/ (needs oiiotool from openimageio-tools).

  python3 fuzz/make_corpus.py

fuzz_image_load seeds: one selector byte (see fuzz_image_load.cpp) + the bytes of a tiny image file:
valid EXR (half/float, zip/piz, tiled, 1 and 4 channels, NaN/Inf/negative texels, 1e30 texels) and
Radiance HDR (flat and run-length encoded) files, plus a few broken ones (truncated, wrong extension,
garbage header). fuzz_table_product seeds: hand-built byte blobs in the layout of fuzz_table_product.cpp.
Everything stays far below 100 KB.
"""
import base64
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(ROOT, "corpus")

# Selector byte of fuzz_image_load: low 4 bits pick the extension.
EXT = {".exr": 0, ".hdr": 1, ".pic": 4, ".png": 7, ".tif": 8, ".ppm": 10, "": 14, ".txt": 15}
LAYOUT = {"auto": 0, "latlong": 1, "equal-area": 2}  # bits 4-5
SCALE = {1.0: 0, 0.0: 1, 1e30: 2, 1e-30: 3}  # bits 6-7


def selector(ext, layout="auto", scale=1.0):
    return bytes([EXT[ext] | LAYOUT[layout] << 4 | SCALE[scale] << 6])


def oiiotool(tmp, name, *args):
    """The bytes of an image file written by oiiotool, without software/history metadata and with a
    fixed capture date (same length, so the file stays valid): the corpus is reproducible."""
    path = os.path.join(tmp, name)
    subprocess.run(["oiiotool", "--nosoftwareattrib", *args, "-o", path], check=True)
    with open(path, "rb") as f:
        return re.sub(rb"\d{4}:\d\d:\d\d \d\d:\d\d:\d\d", b"2000:01:01 00:00:00", f.read())


def claim_size(exr, width, height):
    """The EXR with its data and display windows claiming width x height texels (the data stays)."""
    b = bytearray(exr)
    for key in (b"dataWindow\0box2i\0", b"displayWindow\0box2i\0"):
        at = b.index(key) + len(key) + 4
        b[at:at + 16] = struct.pack("<4i", 0, 0, width - 1, height - 1)
    return bytes(b)


def image_seeds(tmp):
    p = "--pattern"
    half_rgb = oiiotool(tmp, "a.exr", p, "constant:color=1,0.5,0.25", "8x4", "3", "-d", "half")
    sky = oiiotool(tmp, "b.exr", p, "fill:top=0.2,0.4,1:bottom=1,0.8,0.5", "16x8", "3", "-d", "float",
                   "--compression", "zip")
    checker = oiiotool(tmp, "c.exr", p, "checker:width=2:height=2:color1=4,4,4:color2=0,0,0", "16x16", "4",
                       "-d", "half", "--compression", "piz")
    gray_tiled = oiiotool(tmp, "f.exr", p, "constant:color=0.5", "2x2", "1", "-d", "float", "--tile", "16", "16")
    bad_texels = oiiotool(tmp, "n.exr", p, "constant:color=nan,inf,-2", "4x2", "3", "-d", "float")
    huge = oiiotool(tmp, "h.exr", p, "constant:color=1e30,1,0", "4x2", "3", "-d", "float")
    hdr_rle = oiiotool(tmp, "d.hdr", p, "fill:top=0.1,0.2,0.9:bottom=2,1,0.5", "16x8", "3")
    hdr_flat = oiiotool(tmp, "e.hdr", p, "constant:color=3,2,1", "4x2", "3")
    png = oiiotool(tmp, "p.png", p, "constant:color=1,0.5,0", "4x4", "3", "-d", "uint8")
    ppm = oiiotool(tmp, "q.ppm", p, "constant:color=1,0.5,0", "4x2", "3", "-d", "uint8")
    return {
        "exr_half_rgb": selector(".exr") + half_rgb,
        "exr_float_zip_latlong": selector(".exr", "latlong") + sky,
        "exr_rgba_piz_equal_area": selector(".exr", "equal-area") + checker,
        "exr_gray_tiled": selector(".exr") + gray_tiled,
        "exr_nan_inf_negative": selector(".exr") + bad_texels,
        "exr_1e30_scaled": selector(".exr", "auto", 1e30) + huge,
        "exr_truncated": selector(".exr") + sky[: len(sky) // 2],
        "exr_as_hdr": selector(".hdr") + half_rgb,
        # CI's find: a converting read_image() sized a 256-scanline buffer from this claim (12 GB).
        "exr_claims_8M_wide": selector(".exr") + claim_size(half_rgb, 8000000, 2),
        "exr_claims_2M_wide": selector(".exr") + claim_size(half_rgb, 2000000, 2),
        "hdr_rle": selector(".hdr") + hdr_rle,
        "hdr_flat_scale0": selector(".hdr", "auto", 0.0) + hdr_flat,
        "hdr_truncated": selector(".hdr") + hdr_rle[: len(hdr_rle) - 40],
        "hdr_as_pic": selector(".pic") + hdr_flat,
        "hdr_header_only": selector(".hdr") + b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 4\n",
        "png_rgb8": selector(".png") + png,
        "ppm_rgb8": selector(".ppm") + ppm,
        "no_extension_exr": selector("") + half_rgb,
        "garbage_txt": selector(".txt") + b"not an image\n",
        "empty_exr": selector(".exr"),
    }


def f32(*values):
    return b"".join(struct.pack("<f", v) for v in values)


SPECIAL = {"0": 0, "-0": 1, "1": 2, "-1": 3, "nan": 4, "inf": 5, "-inf": 6, "1e30": 7, "-1e30": 8,
           "max": 9, "min": 10, "denorm": 11, "1e-30": 12, "0.5": 13, "1e-7": 14, "2": 15}


def enc(*values):
    """Floats in fuzz_table_product's 4-byte encoding. A name from SPECIAL (or 0) uses the special
    table; |v| < 8 the moderate form int16 / 4096 (rounded to the nearest 1/4096); anything else the
    raw IEEE bytes, whose first byte must be >= 0xa0 (so the lowest mantissa byte may be nudged: a
    relative change below 1e-5)."""
    out = b""
    for v in values:
        if isinstance(v, str) or v == 0:
            out += bytes([0x00, SPECIAL[v if isinstance(v, str) else "0"], 0, 0])
        elif abs(v) < 7.99:
            q = round(v * 4096)
            out += bytes([0x30]) + struct.pack("<h", q) + b"\0"
        else:
            b = bytearray(struct.pack("<f", v))
            b[0] = max(b[0], 0xA0)
            out += bytes(b)
    return out


def header(width, height, flags, top, floor=0, fine=0, scale=0, mix=0, min_alpha=0, angle=0, seed=b"\0" * 6):
    return bytes([width - 1, height - 1, flags, top - 1, floor, fine, scale, mix, min_alpha, angle]) + seed


# flags: bits 0-1 layout (0 auto, 1 latlong, 2 equal-area), 4 compensated, 8 scalar kernel,
# bits 4-5 transform (0 hybrid, 1 slides, 2 abstract), 0x40 rotate, 0x80 proxy via add_* calls
ADD = 0x80


def table_seeds():
    sky = []
    for y in range(16):
        for x in range(32):
            sun = 40.0 if (x, y) in ((20, 4), (21, 4)) else 0.0
            sky += [0.2 + 0.02 * y + sun, 0.3 + sun, 0.8 - 0.03 * y + sun]
    return {
        # 32x16 lat-long sky with a sun, T = 12, diffuse + glossy, n up, wo 30 degrees off
        "sky_diffuse_glossy": header(32, 16, 1 | ADD, 12, seed=b"sky!!!") + enc(0, 0, 1, 0.5, 0, 0.866)
        + enc(0.3, 0, 0.7, 0, 0.2, 0, 1.0) + enc(*sky),
        # 16x16 equal-area with NaN / Inf / negative texels, T = 20, floor 0, compensated, glass seen from below
        "equal_area_bad_texels_glass": header(16, 16, 2 | 4 | ADD, 20, floor=1, mix=2, seed=b"glass!")
        + enc(0, 0, 1, 0.2, 0.1, -0.97) + enc(0, 0, 0.1, 0.9, 0.05, 0.1, 1.5)
        + enc("nan", "inf", "-1", "1e30", "0.5", "2", "-inf", "0", "1", "denorm", "1e-30", "max"),
        # 1x1 map, T = 1, mirror (alpha 0), min_alpha 0
        "one_texel_mirror": header(1, 1, ADD, 1, min_alpha=1) + enc(0, 1, 0, 0, 0.7, 0.7)
        + enc(0, 0, 1, 0, 0, 0, 1) + enc(2.0, 1.0, 0.5),
        # all-black map: an empty table
        "all_black": header(8, 4, 1, 12) + enc(0, 0, 1, 0, 0, 1) + enc(1, 0, 0, 0, 0, 0, 1) + enc("0"),
        # 1x64 column of 1e30 texels times scale 3e38, T = 7, fine resolution 50
        "huge_texels": header(1, 64, 1 | ADD, 7, fine=128 + 49, scale=5) + enc(1, 1, 1, -1, 1, 1)
        + enc(1, 1, 1, 0, 0.5, 0.5, 1.3) + enc("1e30", "max", "1"),
        # degenerate shading point: zero normal, NaN wo
        "zero_normal_nan_wo": header(4, 2, 0, 5) + enc("0", "0", "0", "nan", "1", "0")
        + enc(1, 0, 1, 0, 0.3, 0, 1),
        # unvalidated proxy fields: NaN, negative and infinite weights, roughness out of range, IOR 0
        "raw_proxy_nan_weights": header(8, 8, 2 | 0x40, 6, angle=77) + enc(0.1, 0.2, 0.9, 0.5, -0.2, 0.3)
        + enc("nan", "-1", "inf", "max", "-1", "2", "0") + enc(1, 2, 3, 0.1, 0.1, 0.1),
        # 3x1 map, T = 2, env_mix 0.5, scalar kernel, abstract transform, IOR below 1 (TIR)
        "three_by_one_tir": header(3, 1, 1 | 8 | 0x20 | ADD, 2, mix=3, floor=3) + enc(0, 0, 1, 0.9, 0, 0.1)
        + enc(0, 0, 0.2, 0.8, 0.3, 0.2, 0.67) + enc(5, 0, 0, 0, 5, 0, 0, 0, 5),
        # grazing view, rough everything, slides transform, fine resolution 1
        "grazing_rough": header(64, 32, 1 | 0x10 | ADD, 16, fine=128, mix=5) + enc(0, 0, 1, 1, 0, 1e-4)
        + enc(0.1, 0.1, 0.5, 0.3, 1, 1, 1.33) + enc(*sky[:96]),
    }


# Inputs that once failed, kept as seeds so that every run replays them first.
REGRESSIONS = {
    "fuzz_table_product": {
        # ProductSampler::prepare with a denormal translucent weight (4.4e-39): the product-weight sum
        # was below FLT_MIN, 1/sum overflowed and every pdf was inf (fixed in src/product_sampler.cpp).
        "regress_denormal_proxy_weight":
        "QD+ABgCxBQAAAAAAAAAAADAAEAAwABAAMAAQADAA8AAwADAAEAAwABAAMADwADAAEAAwABAAMAAQQDAAEAAwABB+AAAABwAAAAkAAAACAAA=",
        # ProductSampler::prepare with a refraction weight of FLT_MAX: a product weight was inf, the
        # environment fallback computed 0 * inf = NaN and prepare() returned invalid for a valid shading
        # point (fixed in src/product_sampler.cpp).
        "regress_infinite_product_weight":
        "AgCpAQMAAM0EADAzAwAwuAoAMABQAAAAMAAQADBmDgAAAAAAMJoBAAAAAAAAAAAAMDMDAgCpAQMAAM0EADAzAwAwuAoAMABQAAAAMAAQADBm"
        "DgAAAAAAMJoBAAAAAAAAAAAAMDMDADDNDAAwzQQAMDOlADC4CgAwAFAAAAAAAAAAAAAAAAAAMABQAAAAAAAAAAAAAAAAADAAUAAAMM0MADDN"
        "BAAwM6UAMLgKADAAUAAAAAAAAAAAAAAAAAAwAFAAAAAAAAAAAAAAAAAAMABQAA==",
    },
}


def write(target, seeds):
    d = os.path.join(CORPUS, target)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    for name, data in seeds.items():
        with open(os.path.join(d, name), "wb") as f:
            f.write(data)


def main():
    with tempfile.TemporaryDirectory() as tmp:
        write("fuzz_image_load", image_seeds(tmp))
    seeds = table_seeds()
    seeds.update({k: base64.b64decode(v) for k, v in REGRESSIONS["fuzz_table_product"].items()})
    write("fuzz_table_product", seeds)
    total = sum(os.path.getsize(os.path.join(r, f)) for r, _, fs in os.walk(CORPUS) for f in fs)
    print(f"corpus: {total} bytes")
    if total > 100_000:
        sys.exit("corpus exceeds 100 KB")


if __name__ == "__main__":
    main()
