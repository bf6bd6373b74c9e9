#!/usr/bin/env python3
"""Fixtures for the OpenPose decoding (crates/gait-pose/tests/openpose_decode.rs).

Needs (pip): controlnet-aux==0.0.10, torch (any recent, CPU), opencv-python-headless==4.10.0.84,
scipy==1.17.1, numpy. Regenerate from the repo root:

    /work/venvs/openpose/bin/python tools/openpose/make_decode_fixtures.py

Writes crates/gait-pose/tests/fixtures/openpose/decode/:
- resize.json: cv2.resize results (uint8 images, float32 maps as little-endian hex; CUBIC / LANCZOS4 / AREA,
  explicit dsize and fx/fy factors), with Intel IPP off (OpenCV's own code) and as a default cv2 returns them.
- gaussian.json: scipy.ndimage.gaussian_filter(sigma=3) on float64 maps.
- <case>.json + <case>.bin: synthetic stride-8 network outputs (float16, exactly what the fake
  network handed to controlnet_aux, heatmaps then PAFs per scale, CHW) and the `candidate` /
  `subset` that controlnet_aux's Body.__call__ returned on them (its torch model replaced by a
  module returning these maps). The BODY_25 case cannot run through controlnet_aux (it is
  hard-wired to COCO-18): its expected values come from `decode_numpy` below, the same
  algorithm with OpenPose's BODY_25 tables, which this script first checks against
  controlnet_aux on every COCO case. It is not OpenPose's C++ code.
"""
import inspect
import json
import os
import sys
import textwrap

import cv2
import numpy as np
import scipy
import torch
from scipy.ndimage import gaussian_filter

from controlnet_aux.open_pose import body as body_mod
from controlnet_aux.open_pose import util

OUT = os.path.join(os.path.dirname(__file__), "..", "..", "crates", "gait-pose", "tests", "fixtures", "openpose", "decode")
rng = np.random.default_rng(20261122)


def hexed(a):
    """Raw little-endian bytes (uint8 or float32) as hex: exact and compact."""
    return np.ascontiguousarray(a).astype(a.dtype.newbyteorder("<")).tobytes().hex()


def resize_fixtures():
    cases = []
    img = rng.integers(0, 256, size=(29, 37, 3), dtype=np.uint8)
    img2 = rng.integers(0, 256, size=(28, 36, 3), dtype=np.uint8)
    big = rng.integers(0, 256, size=(61, 83, 3), dtype=np.uint8)
    fmap = (rng.standard_normal((9, 7)) * 2.0).astype(np.float32)
    fmap2 = (rng.standard_normal((23, 31))).astype(np.float32)

    def resize(src, interp, dsize, f):
        if dsize is not None:
            return cv2.resize(src, dsize, interpolation=interp)
        return cv2.resize(src, (0, 0), fx=f, fy=f, interpolation=interp)

    def add(name, src, interp, dsize=None, f=None):
        # opencv-python routes some resizes (INTER_CUBIC at least) through Intel IPP, whose
        # arithmetic is not OpenCV's own; "dst" is OpenCV's own code (IPP off), "dst_default"
        # what a default cv2 returns (null where the same).
        default = resize(src, interp, dsize, f)
        cv2.ipp.setUseIPP(False)
        out = resize(src, interp, dsize, f)
        cv2.ipp.setUseIPP(True)
        assert cv2.ipp.useIPP()
        cases.append({
            "name": name,
            "dtype": str(src.dtype),
            "interp": {cv2.INTER_CUBIC: "cubic", cv2.INTER_LANCZOS4: "lanczos4", cv2.INTER_AREA: "area"}[interp],
            "src_shape": list(src.shape),
            "src": hexed(src),
            "dsize": list(dsize) if dsize is not None else None,
            "factor": f,
            "dst_shape": list(out.shape),
            "dst": hexed(out),
            "dst_default": None if np.array_equal(default, out) else hexed(default),
        })

    for interp in (cv2.INTER_CUBIC, cv2.INTER_LANCZOS4):
        add("u8_up_factor", img, interp, f=1.7)
        add("u8_down_factor", img, interp, f=0.45)
        add("u8_down_odd", img, interp, dsize=(13, 11))
        add("u8_up_odd", img, interp, dsize=(61, 47))
        add("f32_up8", fmap, interp, dsize=(56, 72))
        add("f32_up8_factor", fmap, interp, f=8)
        add("f32_down_odd", fmap2, interp, dsize=(13, 11))
        add("f32_up_odd", fmap2, interp, dsize=(45, 39))
    add("u8_big_down", big, cv2.INTER_CUBIC, dsize=(35, 27))
    add("u8_area_odd", img, cv2.INTER_AREA, dsize=(13, 11))
    add("u8_area_big", big, cv2.INTER_AREA, dsize=(29, 23))
    add("u8_area_2x", img2, cv2.INTER_AREA, dsize=(18, 14))
    add("u8_area_3x", big[:60, :81], cv2.INTER_AREA, dsize=(27, 20))
    add("u8_area_factor", big, cv2.INTER_AREA, f=0.3)
    add("f32_area_odd", fmap2, cv2.INTER_AREA, dsize=(13, 11))
    add("f32_area_near1", fmap2, cv2.INTER_AREA, dsize=(29, 20))
    with open(os.path.join(OUT, "resize.json"), "w") as fh:
        json.dump({"opencv": cv2.__version__, "cases": cases}, fh)


def gaussian_fixtures():
    cases = []
    m = rng.random((23, 31)) * 0.2
    m[5, 7] += 3.0
    m[17, 25] += 1.5
    for name, a in [("map", m), ("tiny", rng.random((2, 3))), ("column", rng.random((30, 1)))]:
        out = gaussian_filter(a, sigma=3)
        cases.append({"name": name, "shape": list(a.shape), "src": a.ravel().tolist(), "dst": out.ravel().tolist()})
    with open(os.path.join(OUT, "gaussian.json"), "w") as fh:
        json.dump({"scipy": scipy.__version__, "cases": cases}, fh)


# ---- synthetic people ---------------------------------------------------------------

COCO_LIMBS = [(1, 2), (1, 5), (2, 3), (3, 4), (5, 6), (6, 7), (1, 8), (8, 9), (9, 10), (1, 11), (11, 12), (12, 13),
              (1, 0), (0, 14), (14, 16), (0, 15), (15, 17), (2, 16), (5, 17)]
COCO_PAF = [(12, 13), (20, 21), (14, 15), (16, 17), (22, 23), (24, 25), (0, 1), (2, 3), (4, 5), (6, 7), (8, 9),
            (10, 11), (28, 29), (30, 31), (34, 35), (32, 33), (36, 37), (18, 19), (26, 27)]
COCO_STARTS = [k < 17 for k in range(19)]
# OpenPose src/openpose/pose/poseParameters.cpp, BODY_25 POSE_BODY_PART_PAIRS and POSE_MAP_INDEX.
B25_PAIRS = [1, 8, 1, 2, 1, 5, 2, 3, 3, 4, 5, 6, 6, 7, 8, 9, 9, 10, 10, 11, 8, 12, 12, 13, 13, 14, 1, 0, 0, 15, 15, 17,
             0, 16, 16, 18, 2, 17, 5, 18, 14, 19, 19, 20, 14, 21, 11, 22, 22, 23, 11, 24]
B25_MAP = [0, 1, 14, 15, 22, 23, 16, 17, 18, 19, 24, 25, 26, 27, 6, 7, 2, 3, 4, 5, 8, 9, 10, 11, 12, 13, 30, 31, 32, 33,
           36, 37, 34, 35, 38, 39, 20, 21, 28, 29, 40, 41, 42, 43, 44, 45, 46, 47, 48, 49, 50, 51]
B25_LIMBS = list(zip(B25_PAIRS[0::2], B25_PAIRS[1::2]))
B25_PAF = list(zip(B25_MAP[0::2], B25_MAP[1::2]))
B25_STARTS = [pair not in ((2, 17), (5, 18)) for pair in B25_LIMBS]

# A standing person, COCO-18 order, unit height (x right, y down), centred on x = 0.
COCO_TEMPLATE = np.array([
    [0.0, 0.0], [0.0, 0.12], [-0.1, 0.13], [-0.14, 0.3], [-0.16, 0.45], [0.1, 0.13], [0.15, 0.3], [0.17, 0.46],
    [-0.07, 0.5], [-0.08, 0.73], [-0.09, 0.95], [0.07, 0.5], [0.08, 0.73], [0.09, 0.95],
    [-0.03, -0.02], [0.03, -0.02], [-0.06, 0.0], [0.06, 0.0]])
# BODY_25 from the COCO template: mid hip, and toes/heels below the ankles.
_c = COCO_TEMPLATE
B25_TEMPLATE = np.array([
    _c[0], _c[1], _c[2], _c[3], _c[4], _c[5], _c[6], _c[7], (_c[8] + _c[11]) / 2, _c[8], _c[9], _c[10], _c[11], _c[12],
    _c[13], _c[14], _c[15], _c[16], _c[17],
    _c[13] + [0.05, 0.04], _c[13] + [0.09, 0.035], _c[13] + [-0.02, 0.045],
    _c[10] + [-0.05, 0.04], _c[10] + [-0.09, 0.035], _c[10] + [0.02, 0.045]])


def person(template, cx, top, height, missing=(), jitter=0.01, lean=0.0):
    p = template.copy()
    p[:, 0] += lean * p[:, 1]
    p = p + rng.normal(0, jitter, p.shape)
    pts = np.stack([cx + p[:, 0] * height, top + p[:, 1] * height], axis=1)
    return [None if i in missing else (float(pts[i, 0]), float(pts[i, 1])) for i in range(len(p))]


def render(people, limbs, paf_idx, n_parts, n_paf, out_h, out_w, mult, distractors=(), noise=True):
    """Stride-8 maps for a padded input whose output is out_h x out_w; keypoints in image px."""
    heat = np.zeros((n_parts + 1, out_h, out_w), np.float32)
    paf = np.zeros((n_paf, out_h, out_w), np.float32)
    cnt = np.zeros((len(limbs), out_h, out_w), np.float32)
    yy, xx = np.mgrid[0:out_h, 0:out_w].astype(np.float32)

    def to_out(pt):
        return ((pt[0] * mult - 3.5) / 8.0, (pt[1] * mult - 3.5) / 8.0)

    for kps in people:
        for i, pt in enumerate(kps):
            if pt is None:
                continue
            ox, oy = to_out(pt)
            heat[i] = np.maximum(heat[i], np.exp(-((xx - ox) ** 2 + (yy - oy) ** 2) / (2 * 1.0 ** 2)))
        for k, (a, b) in enumerate(limbs):
            if kps[a] is None or kps[b] is None:
                continue
            ax, ay = to_out(kps[a])
            bx, by = to_out(kps[b])
            v = np.array([bx - ax, by - ay])
            ln = np.linalg.norm(v)
            if ln < 1e-6:
                continue
            u = v / ln
            px, py = xx - ax, yy - ay
            along = px * u[0] + py * u[1]
            across = np.abs(px * u[1] - py * u[0])
            on = (along >= -0.5) & (along <= ln + 0.5) & (across <= 1.0)
            paf[paf_idx[k][0]][on] += u[0]
            paf[paf_idx[k][1]][on] += u[1]
            cnt[k][on] += 1
    for k in range(len(limbs)):
        c = np.maximum(cnt[k], 1)
        paf[paf_idx[k][0]] /= c
        paf[paf_idx[k][1]] /= c
    for part, pt, amp in distractors:
        ox, oy = to_out(pt)
        heat[part] = np.maximum(heat[part], amp * np.exp(-((xx - ox) ** 2 + (yy - oy) ** 2) / 2.0))
    if noise:
        heat[:n_parts] += rng.random(heat[:n_parts].shape).astype(np.float32) * 0.02
        paf += (rng.random(paf.shape).astype(np.float32) - 0.5) * 0.04
    heat[n_parts] = np.clip(1.0 - heat[:n_parts].max(axis=0), 0, 1)
    # float16 on purpose: the fixture stores exactly these values.
    return heat.astype(np.float16).astype(np.float32), paf.astype(np.float16).astype(np.float32)


def scale_geometry(h, w, scale_search):
    geo = []
    for s in scale_search:
        m = s * 368 / h
        dummy = np.zeros((h, w, 3), np.uint8)
        small = util.smart_resize_k(dummy, fx=m, fy=m)
        padded, pad = util.padRightDownCorner(small, 8, 128)
        geo.append((m, small.shape[0], small.shape[1], padded.shape[0], padded.shape[1]))
    return geo


class FakeNet(torch.nn.Module):
    """Stands in for bodypose_model: returns (PAFs, heatmaps) prepared for each scale in turn."""

    def __init__(self, outputs, geo):
        super().__init__()
        self.dummy = torch.nn.Parameter(torch.zeros(1))
        self.outputs = list(outputs)
        self.geo = list(geo)
        self.calls = 0

    def forward(self, x):
        _, _, ph, pw = self.geo[self.calls][:]
        assert tuple(x.shape) == (1, 3, ph, pw), (x.shape, ph, pw)
        heat, paf = self.outputs[self.calls]
        self.calls += 1
        return torch.from_numpy(paf[None]), torch.from_numpy(heat[None])


def run_controlnet_aux(h, w, outputs, geo, scale_search):
    body = body_mod.Body.__new__(body_mod.Body)
    body.model = FakeNet(outputs, [g[1:] for g in geo])
    # controlnet_aux hard-codes `scale_search = [0.5]`; for other scale lists run the same
    # function's source with that one line replaced (nothing else changes).
    if list(scale_search) != [0.5]:
        src = textwrap.dedent(inspect.getsource(body_mod.Body.__call__))
        line = "scale_search = [0.5]"
        assert src.count(line) == 1
        src = src.replace(line, "scale_search = " + repr(list(scale_search)))
        ns = {}
        exec(compile(src, body_mod.__file__, "exec"), body_mod.__dict__, ns)
        fn = ns["__call__"]
    else:
        fn = body_mod.Body.__call__
    img = rng.integers(0, 256, size=(h, w, 3), dtype=np.uint8)
    cand, subset = fn(body, img)
    assert body.model.calls == len(scale_search)
    return np.asarray(cand, np.float64).reshape(-1, 4), np.asarray(subset, np.float64)


def full_maps(h, w, outputs, geo, n_heat, n_paf):
    """controlnet_aux's map pipeline (its own util functions) for any channel count."""
    heat_avg = np.zeros((h, w, n_heat))
    paf_avg = np.zeros((h, w, n_paf))
    for (heat, paf), (m, sh, sw, ph, pw) in zip(outputs, geo):
        for src, avg, is_heat in ((heat, heat_avg, True), (paf, paf_avg, False)):
            x = np.transpose(src, (1, 2, 0))
            x = util.smart_resize_k(x, fx=8, fy=8)
            x = x[:sh, :sw, :]
            x = util.smart_resize(x, (h, w))
            if is_heat:
                avg += avg + x / len(outputs)
            else:
                avg += + x / len(outputs)
    return heat_avg, paf_avg


def decode_numpy(heat_avg, paf_avg, n_parts, limbs, paf_idx, starts, thre1=0.1, thre2=0.05):
    """controlnet_aux's decoding written out for any limb table (same algorithm and order)."""
    H = heat_avg.shape[0]
    all_peaks, counter = [], 0
    for part in range(n_parts):
        ori = heat_avg[:, :, part]
        sm = gaussian_filter(ori, sigma=3)
        pad = np.pad(sm, 1)
        c = pad[1:-1, 1:-1]
        ok = (c >= pad[:-2, 1:-1]) & (c >= pad[2:, 1:-1]) & (c >= pad[1:-1, :-2]) & (c >= pad[1:-1, 2:]) & (c > thre1)
        ys, xs = np.nonzero(ok)
        all_peaks.append([(int(x), int(y), float(ori[y, x]), counter + i) for i, (x, y) in enumerate(zip(xs, ys))])
        counter += len(xs)
    conns = []
    for k, (a, b) in enumerate(limbs):
        ca, cb = all_peaks[a], all_peaks[b]
        if not ca or not cb:
            conns.append(None)
            continue
        cands = []
        for i, pa in enumerate(ca):
            for j, pb in enumerate(cb):
                vx, vy = pb[0] - pa[0], pb[1] - pa[1]
                norm = max(0.001, float(np.sqrt(vx * vx + vy * vy)))
                xs = np.linspace(pa[0], pb[0], num=10)
                ys = np.linspace(pa[1], pb[1], num=10)
                sx = np.array([paf_avg[int(round(y)), int(round(x)), paf_idx[k][0]] for x, y in zip(xs, ys)])
                sy = np.array([paf_avg[int(round(y)), int(round(x)), paf_idx[k][1]] for x, y in zip(xs, ys)])
                s = sx * (vx / norm) + sy * (vy / norm)
                score = sum(s) / len(s) + min(0.5 * H / norm - 1, 0)
                if np.count_nonzero(s > thre2) > 0.8 * len(s) and score > 0:
                    cands.append((i, j, score))
        cands.sort(key=lambda t: t[2], reverse=True)
        chosen, ui, uj = [], set(), set()
        for i, j, s in cands:
            if i not in ui and j not in uj:
                ui.add(i)
                uj.add(j)
                chosen.append((ca[i][3], cb[j][3], s))
                if len(chosen) >= min(len(ca), len(cb)):
                    break
        conns.append(chosen)
    cand = [p for ps in all_peaks for p in ps]
    rows = []  # [parts (list), score, count]
    for k, (a, b) in enumerate(limbs):
        if conns[k] is None:
            continue
        for ida, idb, s in conns[k]:
            hits = [j for j, r in enumerate(rows) if r[0][a] == ida or r[0][b] == idb]
            if len(hits) == 1:
                r = rows[hits[0]]
                if r[0][b] != idb:
                    r[0][b] = idb
                    r[2] += 1
                    r[1] += cand[idb][2] + s
            elif len(hits) == 2:
                r1, r2 = rows[hits[0]], rows[hits[1]]
                if not any(x >= 0 and y >= 0 for x, y in zip(r1[0], r2[0])):
                    r1[0] = [x if y < 0 else y for x, y in zip(r1[0], r2[0])]
                    r1[1] += r2[1]
                    r1[2] += r2[2]
                    r1[1] += s
                    del rows[hits[1]]
                else:
                    r1[0][b] = idb
                    r1[2] += 1
                    r1[1] += cand[idb][2] + s
            elif not hits and starts[k]:
                parts = [-1] * n_parts
                parts[a], parts[b] = ida, idb
                rows.append([parts, cand[ida][2] + cand[idb][2] + s, 2])
            assert len(hits) <= 2
    rows = [r for r in rows if not (r[2] < 4 or r[1] / r[2] < 0.4)]
    subset = np.array([r[0] + [r[1], r[2]] for r in rows], np.float64).reshape(-1, n_parts + 2)
    return np.array(cand, np.float64).reshape(-1, 4), subset


def save_case(name, model, h, w, scale_search, outputs, geo, cand, subset):
    blobs = []
    scales = []
    for (heat, paf), (m, sh, sw, ph, pw) in zip(outputs, geo):
        assert heat.shape[1:] == (ph // 8, pw // 8)
        scales.append({"out_h": ph // 8, "out_w": pw // 8, "scaled_h": sh, "scaled_w": sw, "padded_h": ph, "padded_w": pw})
        blobs += [heat.astype(np.float16).ravel(), paf.astype(np.float16).ravel()]
    np.concatenate(blobs).astype("<f2").tofile(os.path.join(OUT, name + ".bin"))
    meta = {"name": name, "model": model, "height": h, "width": w, "scales": list(scale_search), "maps": scales,
            "candidate": cand.tolist(), "subset": subset.tolist()}
    with open(os.path.join(OUT, name + ".json"), "w") as fh:
        json.dump(meta, fh)
    print(f"{name}: {len(cand)} peaks, {len(subset)} people", file=sys.stderr)


def coco_case(name, h, w, scale_search, people, distractors=(), noise=True):
    geo = scale_geometry(h, w, scale_search)
    outputs = [render(people, COCO_LIMBS, COCO_PAF, 18, 38, ph // 8, pw // 8, m, distractors, noise)
               for (m, sh, sw, ph, pw) in geo]
    cand, subset = run_controlnet_aux(h, w, outputs, geo, scale_search)
    heat_avg, paf_avg = full_maps(h, w, outputs, geo, 19, 38)
    c2, s2 = decode_numpy(heat_avg, paf_avg, 18, COCO_LIMBS, COCO_PAF, COCO_STARTS)
    # The generic numpy decoding must equal controlnet_aux's before it is trusted for BODY_25.
    assert np.array_equal(c2, cand), name
    assert s2.shape == subset.shape and np.array_equal(s2[:, :-2], subset[:, :-2]), name
    assert np.allclose(s2[:, -2:], subset[:, -2:], rtol=0, atol=1e-9), name
    save_case(name, "coco18", h, w, scale_search, outputs, geo, cand, subset)


def main():
    os.makedirs(OUT, exist_ok=True)
    resize_fixtures()
    gaussian_fixtures()
    T = COCO_TEMPLATE
    coco_case("single", 240, 320, [0.5], [person(T, 150, 30, 190)])
    coco_case("three_crossing", 240, 320, [0.5], [
        person(T, 90, 25, 200, lean=0.1),
        person(T, 135, 35, 185, lean=-0.15),
        person(T, 250, 40, 170, missing=(16, 17)),
    ], distractors=[(4, (300.0, 20.0), 0.9)])
    coco_case("missing_limbs", 240, 320, [0.5], [
        person(T, 80, 30, 190, missing=(5, 6, 7, 12, 13)),
        person(T, 200, 20, 200, missing=(0, 14, 15, 16, 17, 4)),
        person(T, 290, 150, 60, missing=tuple(range(4, 18))),  # 4 parts in a chain, low scores
    ], distractors=[(10, (30.0, 220.0), 0.7), (0, (310.0, 10.0), 0.5)])
    coco_case("two_scales", 150, 200, [0.5, 1.0], [
        person(T, 60, 15, 120), person(T, 140, 25, 110, lean=0.2, missing=(9, 10))])
    coco_case("three_scales", 240, 320, [0.3, 0.5, 0.7], [
        person(T, 100, 30, 180), person(T, 220, 40, 170, missing=(3, 4))])
    coco_case("empty", 120, 160, [0.5], [], noise=False)

    # BODY_25: same algorithm with OpenPose's tables (decode_numpy, checked above).
    h, w, scale_search = 240, 320, [0.5]
    geo = scale_geometry(h, w, scale_search)
    people = [person(B25_TEMPLATE, 90, 25, 190, lean=0.1), person(B25_TEMPLATE, 140, 30, 185, lean=-0.1, missing=(20, 23)),
              person(B25_TEMPLATE, 250, 40, 170, missing=(17, 18))]
    outputs = [render(people, B25_LIMBS, B25_PAF, 25, 52, ph // 8, pw // 8, m, [(21, (300.0, 225.0), 0.8)])
               for (m, sh, sw, ph, pw) in geo]
    heat_avg, paf_avg = full_maps(h, w, outputs, geo, 26, 52)
    cand, subset = decode_numpy(heat_avg, paf_avg, 25, B25_LIMBS, B25_PAF, B25_STARTS)
    save_case("body25", "body25", h, w, scale_search, outputs, geo, cand, subset)


if __name__ == "__main__":
    main()
