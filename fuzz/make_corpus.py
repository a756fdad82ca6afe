#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Regenerates the seed corpora in fuzz/corpus/ (needs oiiotool from openimageio-tools), or writes the
glTF seeds taken from Debian's assimp-testmodels into a directory (what scripts/fuzz.sh does at run time).

  python3 fuzz/make_corpus.py
  python3 fuzz/make_corpus.py --assimp-gltf DIR   # ASSIMP_MODELS overrides /usr/share/assimp/models

fuzz_image_load seeds: one selector byte (see fuzz_image_load.cpp) + the bytes of a tiny image file:
valid EXR (half/float, zip/piz, tiled, 1 and 4 channels, NaN/Inf/negative texels, 1e30 texels) and
Radiance HDR (flat and run-length encoded) files, plus a few broken ones (truncated, wrong extension,
garbage header). fuzz_table_product seeds: hand-built byte blobs in the layout of fuzz_table_product.cpp.
fuzz_gltf seeds: small generated glTF / GLB files (every material feature the loader maps, cameras, a
mirrored node; broken ones: truncated, wrong version, glTF 1.0, texCoord 1, bad factors...).
Everything committed stays far below 100 KB; the assimp-testmodels files are third-party and copied
only into the fuzzing run's temporary corpus.
"""
import base64
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib

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


# ---- fuzz_gltf ----

ASSIMP_MODELS = os.environ.get("ASSIMP_MODELS", "/usr/share/assimp/models")
# Seeds above this size are left out (2CylinderEngine.glb, 1.8 MB; the Draco-compressed engine, whose
# buffer alone is 155 KB): libFuzzer mutates and re-parses the whole input at every run.
GLTF_MAX_SEED = 160_000
IMAGE_MAX = 8192  # inlined images above this size are replaced by a tiny PNG of the same role


def png(width, height, rgb):
    """An 8-bit RGB PNG (rgb: width * height * 3 values), written by hand: no imaging library needed."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    rows = b"".join(b"\0" + bytes(rgb[y * width * 3:(y + 1) * width * 3]) for y in range(height))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b""))


def data_uri(mime, data):
    return f"data:{mime};base64," + base64.b64encode(data).decode()


def compact(doc):
    return json.dumps(doc, separators=(",", ":")).encode()


def inline_gltf(path):
    """A .gltf file with the buffers and images it references inlined as data: URIs (the harness
    writes the input alone into a directory), or its bytes unchanged when it is not valid JSON.
    Missing resources stay referenced (MissingBin is missing its .bin on purpose)."""
    with open(path, "rb") as f:
        raw = f.read()
    try:
        doc = json.loads(raw)
    except ValueError:
        return raw
    if not isinstance(doc, dict):
        return raw
    base = os.path.dirname(path)
    for key, default_mime in (("buffers", "application/octet-stream"), ("images", "image/png")):
        items = doc.get(key)
        if not isinstance(items, list):
            continue
        for item in items:
            uri = item.get("uri") if isinstance(item, dict) else None
            if not isinstance(uri, str) or uri.startswith("data:") or not os.path.isfile(os.path.join(base, uri)):
                continue
            with open(os.path.join(base, uri), "rb") as f:
                data = f.read()
            mime = default_mime
            if key == "images":
                mime = "image/jpeg" if data[:2] == b"\xff\xd8" else "image/png"
                if len(data) > IMAGE_MAX:
                    data, mime = png(2, 2, [200, 120, 60, 40, 90, 220, 128, 128, 255, 255, 255, 255]), "image/png"
            item["uri"] = data_uri(mime, data)
    return compact(doc)


def assimp_gltf_seeds():
    """Every glTF 2.0 and 1.0 file of assimp-testmodels (valid and deliberately broken), self-contained."""
    seeds = {}
    for sub in ("glTF2", "glTF"):
        top = os.path.join(ASSIMP_MODELS, sub)
        if not os.path.isdir(top):
            sys.exit(f"make_corpus: {top} is missing (Debian assimp-testmodels; scripts/install-deps.sh)")
        for root, _, files in sorted(os.walk(top)):
            for name in sorted(files):
                if not name.endswith((".gltf", ".glb")):
                    continue
                path = os.path.join(root, name)
                data = inline_gltf(path) if name.endswith(".gltf") else open(path, "rb").read()
                if len(data) <= GLTF_MAX_SEED:
                    seeds["assimp-" + os.path.relpath(path, ASSIMP_MODELS).replace("/", "-")] = data
    return seeds


def glb(doc, bin_chunk):
    """A GLB container: the JSON chunk (space-padded) and the BIN chunk (zero-padded)."""
    j = compact(doc)
    j += b" " * (-len(j) % 4)
    b = bin_chunk + b"\0" * (-len(bin_chunk) % 4)
    body = struct.pack("<II", len(j), 0x4E4F534A) + j + struct.pack("<II", len(b), 0x004E4942) + b
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


def feature_model(embed_images):
    """A glTF document using every material feature the loader maps, two meshes, two cameras and a
    mirrored, rotated node; its binary data (returned with it) goes into buffer 0. embed_images:
    images in buffer views (GLB) instead of data: URIs."""
    bin_data = b""
    views, accessors = [], []

    def add(data, count, ctype, kind):
        nonlocal bin_data
        bin_data += b"\0" * (-len(bin_data) % 4)
        views.append({"buffer": 0, "byteOffset": len(bin_data), "byteLength": len(data)})
        bin_data += data
        accessors.append({"bufferView": len(views) - 1, "componentType": ctype, "count": count, "type": kind})
        return len(accessors) - 1

    quad_pos = add(f32(-1, 0, 1, 1, 0, 1, 1, 0, -1, -1, 0, -1), 4, 5126, "VEC3")
    accessors[quad_pos].update({"min": [-1, 0, -1], "max": [1, 0, 1]})
    quad_uv = add(f32(0, 1, 1, 1, 1, 0, 0, 0), 4, 5126, "VEC2")
    quad_nrm = add(f32(0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0), 4, 5126, "VEC3")
    quad_idx = add(struct.pack("<6H", 0, 1, 2, 0, 2, 3), 6, 5123, "SCALAR")
    tri_pos = add(f32(0, 0, 0, 1, 0, 0, 0, 1, 0), 3, 5126, "VEC3")
    accessors[tri_pos].update({"min": [0, 0, 0], "max": [1, 1, 0]})
    tri_idx = add(bytes([0, 1, 2]), 3, 5121, "SCALAR")
    images = [png(2, 2, [255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255]),  # base colour
              png(1, 2, [0, 200, 255, 0, 20, 0]),                            # metallic-roughness
              png(1, 1, [173, 189, 230]),                                      # normal
              png(1, 1, [255, 128, 0])]                                        # emissive
    image_json = []
    for data in images:
        if embed_images:
            bin_data += b"\0" * (-len(bin_data) % 4)
            views.append({"buffer": 0, "byteOffset": len(bin_data), "byteLength": len(data)})
            bin_data += data
            image_json.append({"bufferView": len(views) - 1, "mimeType": "image/png"})
        else:
            image_json.append({"uri": data_uri("image/png", data)})
    transform = {"KHR_texture_transform": {"offset": [0.5, 0], "rotation": 0.3, "scale": [2, 2]}}
    doc = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_materials_clearcoat", "KHR_materials_transmission", "KHR_materials_ior",
                           "KHR_materials_emissive_strength", "KHR_texture_transform"],
        "scene": 0,
        "scenes": [{"nodes": [0, 3, 4]}],
        "nodes": [
            {"children": [1, 2], "translation": [0, 1, 0], "rotation": [0, 0.3826834, 0, 0.9238795]},
            {"mesh": 0, "scale": [-1, 1, 1]},
            {"mesh": 1, "matrix": [2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 3, 1]},
            {"camera": 0, "translation": [0, 2, 6]},
            {"camera": 1, "translation": [0, 0, 9]},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.6, "aspectRatio": 1.5, "znear": 0.1}},
                    {"type": "orthographic", "orthographic": {"xmag": 2, "ymag": 1.5, "znear": 0.1, "zfar": 50}}],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": quad_pos, "TEXCOORD_0": quad_uv, "NORMAL": quad_nrm},
                             "indices": quad_idx, "material": 0},
                            {"attributes": {"POSITION": quad_pos}, "indices": quad_idx, "material": 1}]},
            {"primitives": [{"attributes": {"POSITION": tri_pos}, "indices": tri_idx, "material": 2},
                            {"attributes": {"POSITION": tri_pos}, "indices": tri_idx}]},
        ],
        "materials": [
            {"name": "textured", "pbrMetallicRoughness": {
                "baseColorFactor": [1, 0.9, 0.8, 1], "metallicFactor": 0.5, "roughnessFactor": 0.7,
                "baseColorTexture": {"index": 0, "extensions": transform},
                "metallicRoughnessTexture": {"index": 1}},
             "normalTexture": {"index": 2, "scale": 0.8},
             "emissiveTexture": {"index": 3}, "emissiveFactor": [0.2, 0.2, 0.2],
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 3}}},
            {"name": "coated", "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.3, 0.8, 1], "metallicFactor": 0},
             "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 0.8, "clearcoatRoughnessFactor": 0.1}}},
            {"name": "glass", "pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0.05},
             "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1},
                            "KHR_materials_ior": {"ior": 1.45}}},
        ],
        "textures": [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 1}, {"source": 2}, {"source": 3}],
        "samplers": [{"wrapS": 33648, "wrapT": 33071}, {"wrapS": 10497, "wrapT": 10497}],
        "images": image_json,
        "bufferViews": views,
        "accessors": accessors,
        "buffers": [{"byteLength": len(bin_data)}],
    }
    return doc, bin_data


def images_of(doc, i):
    return base64.b64decode(doc["images"][i]["uri"].split(",", 1)[1])


def bad_crc(png_bytes):
    """The PNG with its IDAT chunk's CRC flipped."""
    b = bytearray(png_bytes)
    at = b.index(b"IDAT")
    b[at + 4 + struct.unpack(">I", b[at - 4:at])[0]] ^= 0x55
    return bytes(b)


def gltf_seeds():
    doc, bin_data = feature_model(embed_images=False)
    doc["buffers"][0]["uri"] = data_uri("application/octet-stream", bin_data)
    gdoc, gbin = feature_model(embed_images=True)
    features_glb = glb(gdoc, gbin)

    def variant(change):
        d = json.loads(compact(doc))
        change(d)
        return compact(d)

    def set_path(d, path, value):
        for k in path[:-1]:
            d = d[k]
        d[path[-1]] = value

    # NaN and infinite normals in the file: the loader passes (0, 0, 0), never a non-finite normal.
    nan_bin = bytearray(bin_data)
    at = doc["bufferViews"][2]["byteOffset"]
    nan_bin[at:at + 8] = f32(float("nan"), float("inf"))
    normal_nan = variant(lambda d: set_path(d["buffers"][0], ["uri"], data_uri("application/octet-stream", bytes(nan_bin))))

    return {
        "features.gltf": compact(doc),
        "normal_nan": normal_nan,
        "features.glb": features_glb,
        # broken: the loader must refuse each with one line
        "glb_truncated": features_glb[:300],
        "glb_version_7": features_glb[:4] + struct.pack("<I", 7) + features_glb[8:],
        "glb_magic_only": b"glTF",
        "gltf_1_0": variant(lambda d: set_path(d, ["asset", "version"], "1.0")),
        "json_array": b"[]",
        "json_truncated": compact(doc)[:200],
        "texcoord_1": variant(lambda d: set_path(d, ["materials", 0, "normalTexture", "texCoord"], 1)),
        "roughness_2": variant(lambda d: set_path(d, ["materials", 2, "pbrMetallicRoughness", "roughnessFactor"], 2)),
        "roughness_1e39": variant(lambda d: set_path(d, ["materials", 1, "pbrMetallicRoughness", "roughnessFactor"], 1e39)),
        "bad_wrap_mode": variant(lambda d: set_path(d, ["samplers", 0, "wrapS"], 12345)),
        # libpng reports a bad IDAT checksum on two lines: the loader's error must still be one line.
        "png_crc_error": variant(lambda d: set_path(d, ["images", 0, "uri"], data_uri("image/png", bad_crc(images_of(d, 0))))),
        "image_not_png": variant(lambda d: set_path(d, ["images", 1, "uri"], data_uri("image/png", b"not a png"))),
        "texture_index_9": variant(lambda d: set_path(d, ["materials", 0, "emissiveTexture", "index"], 9)),
        "image_without_source": variant(lambda d: d["textures"][0].pop("source")),
        "remote_image": variant(lambda d: set_path(d, ["images", 0, "uri"], "https://example.com/a.png")),
        "indices_out_of_range": variant(lambda d: set_path(d, ["accessors", 3, "count"], 600)),
        "vertices_huge_scale": variant(lambda d: set_path(d, ["nodes", 1, "scale"], [-1e39, 1, 1])),
        # assimp 5.2 dereferences the missing accessor (a null pointer): refused before assimp reads it.
        "skin_without_inverse_bind_matrices": variant(lambda d: (d.update(skins=[{"joints": [2]}]),
                                                                 set_path(d, ["nodes", 1, "skin"], 0))),
        # assimp 5.2 reads address 1 for a MIME type without '/': refused before assimp reads it.
        "image_mime_without_slash": variant(lambda d: set_path(d, ["images", 0, "uri"],
                                                               d["images"][0]["uri"].replace("image/png", "image5122"))),
        "camera_yfov_0": variant(lambda d: set_path(d, ["cameras", 0, "perspective", "yfov"], 0)),
    }


# Inputs that once failed, kept as seeds so that every run replays them first.
REGRESSIONS = {
    "fuzz_image_load": {
        # A 4x4 RGB PNG (first byte 0x07: the .png extension) whose oFFs chunk has a bad length:
        # OpenImageIO 2.4's PNG reader leaked the 31-byte error string of its read callback when libpng
        # longjmp'd out of it (LeakSanitizer, CI's fuzz run on a fresh machine). EnvironmentMap::load now
        # decodes PNG with libpng's simplified API (src/io/png_decode.h): a one-line error, no leak.
        "regress_png_bad_offs_chunk":
        "B4lQTkcNChoKAAAADUlIRFIAAAAEAAAABAgCAAAAJpMJKQgAAAlvRkZzAAAAAAAAAAAA2iq2zgAAABJJREFUCJkk/N/AAAdMDAzEcABM0QGH/CcDJQAAAABJRU5ErkJggg==",
    },
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
    if len(sys.argv) == 3 and sys.argv[1] == "--assimp-gltf":
        os.makedirs(sys.argv[2], exist_ok=True)
        for name, data in assimp_gltf_seeds().items():
            with open(os.path.join(sys.argv[2], name), "wb") as f:
                f.write(data)
        return
    if len(sys.argv) != 1:
        sys.exit(__doc__)
    with tempfile.TemporaryDirectory() as tmp:
        seeds = image_seeds(tmp)
    seeds.update({k: base64.b64decode(v) for k, v in REGRESSIONS["fuzz_image_load"].items()})
    write("fuzz_image_load", seeds)
    seeds = table_seeds()
    seeds.update({k: base64.b64decode(v) for k, v in REGRESSIONS["fuzz_table_product"].items()})
    write("fuzz_table_product", seeds)
    write("fuzz_gltf", gltf_seeds())
    total = sum(os.path.getsize(os.path.join(r, f)) for r, _, fs in os.walk(CORPUS) for f in fs)
    print(f"corpus: {total} bytes")
    if total > 100_000:
        sys.exit("corpus exceeds 100 KB")


if __name__ == "__main__":
    main()
