#!/usr/bin/env python3
"""Reference decodes of the still-image JPEG inputs in tests/data/jpeg/ (issue 33).

What the Rust JPEG reader must match is `cv2.imread(path, cv2.IMREAD_COLOR)` (OpenCV 4.10, whose
bundled libjpeg-turbo is 3.0.3; EXIF orientation applied as imread does by default), converted
from BGR to RGB. This script writes OpenCV's result, never our Rust code's, and also decodes every
file with Pillow (`ImageOps.exif_transpose(Image.open(p)).convert("RGB")`) and records where the
two disagree (they do on the CMYK file: see README.md).

Needs: the project's Python venv (tools/python/requirements.txt: opencv-contrib-python==4.10.0.84,
pillow==13.0.0, numpy), which tools/python/setup.sh builds into target/python-venv.
Regenerate (from the repository root):
    target/python-venv/bin/python tools/jpeg/make_fixtures.py
It does not touch the JPEG files themselves (they are real files from PyPI packages, see
tests/data/jpeg/README.md). Check only, writing nothing (exit 1 on any difference from what is
committed):
    target/python-venv/bin/python tools/jpeg/make_fixtures.py --check

Writes into tests/data/jpeg/expected/:
  - <name>.png: OpenCV's decode as an 8-bit RGB PNG (lossless, written by cv2.imencode), for
    every file but the full-body photographs in PHOTOS (those have only their sha256, to keep the
    repository small);
  - manifest.json: {"generator": ..., "files": {name: {...}}} with, per JPEG: width and height of
    the decoded (oriented) image, orientation (the EXIF tag value that imread applies, 1 when
    absent), sof (0 baseline, 1 extended, 2 progressive), progressive, sampling (the SOF's H/V
    factors per component, e.g. "22x11x11" = 4:2:0), restart_interval (DRI, 0 = none),
    components, adobe_transform (APP14's transform flag, null without APP14), precision,
    sha256_of_rgb (of OpenCV's RGB bytes, row-major, no padding), png (file name or null),
    pillow_equal / pillow_max_diff / pillow_mismatched_values (Pillow against OpenCV;
    null when Pillow could not decode) and pillow_error.
"""
import hashlib
import json
import os
import re
import struct
import sys

import cv2
import numpy as np
from PIL import Image, ImageOps, features

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
DATA = os.path.join(ROOT, "tests", "data", "jpeg")
OUT = os.path.join(DATA, "expected")
# The full-body photographs (their BlazePose references come from make_pose_fixtures.py): only the
# sha256 of their decode is kept, no PNG, so the fixtures stay small (object_detection_input.jpg alone
# would be 0.44 MB).
PHOTOS = ["audrybt1.jpg", "messi5.jpg", "object_detection_input.jpg"]


def jpeg_info(path: str) -> dict:
    """The JPEG's real properties, read from its markers (not from the file name)."""
    d = open(path, "rb").read()
    if d[:3] != b"\xff\xd8\xff":
        raise ValueError(f"{path}: not a JPEG")
    info = {"sof": None, "restart_interval": 0, "adobe_transform": None, "orientation": 1}
    first_app1 = None
    i = 2
    while i + 4 <= len(d):
        if d[i] != 0xFF:
            i += 1
            continue
        m = d[i + 1]
        if m == 0xFF:
            i += 1
            continue
        if m in (0xD8, 0x01) or 0xD0 <= m <= 0xD7:
            i += 2
            continue
        if m == 0xD9:
            break
        (length,) = struct.unpack(">H", d[i + 2:i + 4])
        seg = d[i + 4:i + 2 + length]
        if 0xC0 <= m <= 0xCF and m not in (0xC4, 0xC8, 0xCC) and info["sof"] is None:
            n = seg[5]
            info.update(
                sof=m - 0xC0,
                progressive=m in (0xC2, 0xC6, 0xCA, 0xCE),
                precision=seg[0],
                components=n,
                sampling="x".join(f"{seg[7 + 3 * k] >> 4}{seg[7 + 3 * k] & 15}" for k in range(n)),
            )
        elif m == 0xDD:
            info["restart_interval"] = struct.unpack(">H", seg[:2])[0]
        elif m == 0xEE and seg[:5] == b"Adobe" and len(seg) >= 12:
            info["adobe_transform"] = seg[11]
        elif m == 0xE1 and first_app1 is None:
            first_app1 = seg
        if m == 0xDA:  # skip the entropy-coded data up to the next marker that is not RSTn
            j = i + 2 + length
            while j + 1 < len(d) and not (d[j] == 0xFF and d[j + 1] != 0 and not 0xD0 <= d[j + 1] <= 0xD7):
                j += 1
            i = j
            continue
        i += 2 + length
    if first_app1 is not None:
        info["orientation"] = opencv_orientation(first_app1)
    return info


def opencv_orientation(app1: bytes) -> int:
    """The orientation imread applies: OpenCV 4.10 (grfmt_jpeg.cpp, exif.cpp) reads only the first
    APP1 segment, skips its 6-byte "Exif\\0\\0" header unchecked, needs "II" or "MM" and 0x002A,
    and takes tag 0x0112 from IFD0 (the first entry with that tag), as a u16 at entry offset 8
    whatever the entry's type; values outside 1..8 leave the image as decoded."""
    t = app1[6:]
    if len(t) < 8 or t[0:2] not in (b"II", b"MM"):
        return 1
    e = "<" if t[:2] == b"II" else ">"
    if struct.unpack(e + "H", t[2:4])[0] != 0x2A:
        return 1
    off = struct.unpack(e + "I", t[4:8])[0]
    try:
        (n,) = struct.unpack(e + "H", t[off:off + 2])
        for k in range(n):
            ent = t[off + 2 + 12 * k:off + 14 + 12 * k]
            if struct.unpack(e + "H", ent[:2])[0] == 0x0112:
                v = struct.unpack(e + "H", ent[8:10])[0]
                return v if 1 <= v <= 8 else 1
    except struct.error:
        pass
    return 1


def opencv_rgb(path: str) -> np.ndarray:
    bgr = cv2.imread(path, cv2.IMREAD_COLOR)
    if bgr is None:
        raise RuntimeError(f"cv2.imread could not read {path}")
    return np.ascontiguousarray(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))


def pillow_rgb(path: str) -> np.ndarray:
    with Image.open(path) as im:
        return np.asarray(ImageOps.exif_transpose(im).convert("RGB"))


def entry(name: str) -> tuple:
    path = os.path.join(DATA, name)
    info = jpeg_info(path)
    rgb = opencv_rgb(path)
    h, w = rgb.shape[:2]
    e = {
        "width": w,
        "height": h,
        "orientation": info["orientation"],
        "sof": info["sof"],
        "progressive": info["progressive"],
        "sampling": info["sampling"],
        "restart_interval": info["restart_interval"],
        "components": info["components"],
        "adobe_transform": info["adobe_transform"],
        "precision": info["precision"],
        "sha256_of_rgb": hashlib.sha256(rgb.tobytes()).hexdigest(),
        "png": None if name in PHOTOS else os.path.splitext(name)[0] + ".png",
        "pillow_equal": None,
        "pillow_max_diff": None,
        "pillow_mismatched_values": None,
        "pillow_error": None,
    }
    try:
        pil = pillow_rgb(path)
    except Exception as ex:  # e.g. the truncated file: Pillow refuses it, imread decodes it
        e["pillow_error"] = f"{type(ex).__name__}: {ex}"
    else:
        if pil.shape != rgb.shape:
            e["pillow_equal"] = False
            e["pillow_error"] = f"shape {pil.shape} against OpenCV's {rgb.shape}"
        else:
            diff = np.abs(pil.astype(np.int16) - rgb.astype(np.int16))
            e["pillow_equal"] = bool(diff.max() == 0)
            e["pillow_max_diff"] = int(diff.max())
            e["pillow_mismatched_values"] = int(np.count_nonzero(diff))
    return e, rgb


def png_bytes(rgb: np.ndarray) -> bytes:
    ok, buf = cv2.imencode(".png", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_PNG_COMPRESSION, 9])
    assert ok
    return buf.tobytes()


def main() -> int:
    check = "--check" in sys.argv[1:]
    names = sorted(n for n in os.listdir(DATA) if n.lower().endswith((".jpg", ".jpeg")))
    m = re.search(r"JPEG:\s*(.*)", cv2.getBuildInformation())
    manifest = {
        "generator": f"cv2.imread(path, cv2.IMREAD_COLOR) then BGR->RGB, opencv {cv2.__version__} "
        f"(JPEG: {m.group(1).strip() if m else '?'}); compared with Pillow {Image.__version__} "
        f"(libjpeg-turbo {features.version('libjpeg_turbo')}) "
        "ImageOps.exif_transpose(Image.open(p)).convert('RGB')",
        "files": {},
    }
    bad = 0
    os.makedirs(OUT, exist_ok=True)
    for name in names:
        e, rgb = entry(name)
        manifest["files"][name] = e
        note = "equal" if e["pillow_equal"] else f"DIFFERS max {e['pillow_max_diff']}" if e["pillow_error"] is None else e["pillow_error"]
        print(f"{name:28s} {e['width']}x{e['height']} orient={e['orientation']} sof={e['sof']} "
              f"{e['sampling']} dri={e['restart_interval']} adobe={e['adobe_transform']}  pillow: {note}")
        if e["png"]:
            png_path = os.path.join(OUT, e["png"])
            if check:
                old = cv2.imread(png_path, cv2.IMREAD_COLOR)
                if old is None or not np.array_equal(cv2.cvtColor(old, cv2.COLOR_BGR2RGB), rgb):
                    print(f"  {e['png']} differs from this decode")
                    bad += 1
            else:
                with open(png_path, "wb") as fh:
                    fh.write(png_bytes(rgb))
    text = json.dumps(manifest, indent=1) + "\n"
    path = os.path.join(OUT, "manifest.json")
    if check:
        if not os.path.exists(path) or json.load(open(path)) != manifest:
            print("manifest.json differs from this run")
            bad += 1
        return 1 if bad else 0
    with open(path, "w") as fh:
        fh.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
