#!/usr/bin/env python3
"""Reference fixtures for the OpenPose networks in crates/gait-pose (candle and ort backends).

Needs: Python 3.11 with torch==2.15.0 (CPU), controlnet-aux==0.0.10, onnx==1.23.2, onnxruntime==1.31.1,
opencv-python-headless==4.10.0.84, numpy (2.x), scipy.
Regenerate (from the repository root; deterministic, takes about a minute):
    python3.11 -m venv /tmp/op && /tmp/op/bin/pip install torch==2.15.0 controlnet-aux==0.0.10 onnx==1.23.2 \
        onnxruntime==1.31.1 opencv-python-headless==4.10.0.84
    /tmp/op/bin/python tools/openpose/make_net_fixtures.py

Real weights cannot be downloaded here, and full-size random weights (~200 MB) cannot be committed, so every
network gets the synthetic weights of synthetic_weights.py (a counter-based formula the Rust tests implement too).
Writes into crates/gait-pose/tests/fixtures/openpose/net/:
  - coco18_manifest.json: every tensor of `body_pose_model.pth` in controlnet_aux's layout: checkpoint name (the
    state_dict key of controlnet_aux's `bodypose_model` without its first component, as `util.transfer` maps
    it), torch key, shape; in state_dict order (= the synthetic formula's tensor index);
  - body25_manifest.json: the same for the BODY_25 torch module of body25_model.py;
  - input_bgr.bin: the test input, u8 HxWx3 BGR, a frame of the sample video resized with controlnet_aux's
    `util.smart_resize_k` and padded to stride 8 with 128 by `util.padRightDownCorner` (as body.py does);
    the network input is these bytes / 256 - 0.5 in CHW order;
  - coco18_torch.bin: controlnet_aux's `bodypose_model` output on it (f32 LE: stage-6 heatmaps L2, then PAFs L1);
  - body25_torch.bin: the BODY_25 module's output (f32 LE: 26 heatmaps then 52 PAFs, its single output);
  - coco18.onnx, body25.onnx: torch.onnx exports of the same modules (export_onnx.export) whose initializers are
    external data in a file that is NOT committed; *.onnx.weights.json lists for each initializer its name,
    offset, length, shape and the manifest index of the synthetic tensor it holds, so a test can rebuild it;
  - tiny_zip.pth, tiny_legacy.pth: a few tensors of the real checkpoint layout (synthetic values) written by
    torch.save in the zip format and in the legacy (pre-1.6) format, for the .pth reader;
  - cases.json: sizes of all of the above.
"""
import json
import os
import shutil
import sys
import tempfile
from collections import OrderedDict

import cv2
import numpy as np
import onnx
import onnxruntime as ort
import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import synthetic_weights as sw  # noqa: E402
from body25_model import Body25  # noqa: E402
from export_onnx import checkpoint_key, coco18_model, export  # noqa: E402
from controlnet_aux.open_pose import util  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
OUT = os.path.join(ROOT, "crates/gait-pose/tests/fixtures/openpose/net")
FRAME = os.path.join(ROOT, "crates/gait-pose/tests/fixtures/blazepose/frame_100.png")
SCALE = 0.35  # 640x360 -> 224x126, padded to 224x128: output 28x16 (non-square on purpose)


def manifest_of(model, rename):
    return [{"name": rename(k), "torch": k, "shape": list(v.shape)} for k, v in model.state_dict().items()]


def set_synthetic(model, manifest):
    sd = {m["torch"]: torch.from_numpy(sw.tensor(k, m["name"], m["shape"])) for k, m in enumerate(manifest)}
    model.load_state_dict(sd)
    return sd


def write_onnx(model, name, outputs, manifest, sd, x, reference):
    """Exports with external data, writes the graph and its sidecar, checks onnxruntime against torch."""
    tmp = tempfile.mkdtemp()
    try:
        path = os.path.join(tmp, f"{name}.onnx")
        weights = f"{name}.weights.bin"
        with torch.no_grad():
            export(model, path, outputs, external_location=weights)
        m = onnx.load(path, load_external_data=False)
        by_bytes = {}
        for k, e in enumerate(manifest):
            by_bytes.setdefault(sd[e["torch"]].numpy().tobytes(), []).append(k)
        blob = open(os.path.join(tmp, weights), "rb").read()
        entries = []
        for init in m.graph.initializer:
            ext = {kv.key: kv.value for kv in init.external_data}
            if init.data_location != onnx.TensorProto.EXTERNAL or ext.get("location") != weights:
                raise SystemExit(f"initializer {init.name} is not in {weights}")
            if init.data_type != onnx.TensorProto.FLOAT:
                raise SystemExit(f"initializer {init.name} is not f32")
            off, length = int(ext.get("offset", 0)), int(ext["length"])
            # The exporter may rename initializers: identify each one by its exact bytes.
            ks = by_bytes.get(blob[off:off + length])
            if not ks:
                raise SystemExit(f"initializer {init.name} matches no synthetic tensor (folded?)")
            entries.append({"name": init.name, "offset": off, "length": length, "shape": list(init.dims),
                            "tensor": ks[0], "torch": manifest[ks[0]]["torch"]})
        used = {e["tensor"] for e in entries}
        if len(used) != len(manifest):
            raise SystemExit(f"{name}: {len(manifest) - len(used)} torch tensors not in the ONNX graph")
        sess = ort.InferenceSession(path, providers=["CPUExecutionProvider"])
        got = sess.run(None, {"image": x})
        err = max(float(np.abs(g - r).max() / np.abs(r).max()) for g, r in zip(got, reference))
        print(f"{name}: onnxruntime vs torch max rel err {err:.2e}", file=sys.stderr)
        shutil.copy(path, os.path.join(OUT, f"{name}.onnx"))
        with open(os.path.join(OUT, f"{name}.onnx.weights.json"), "w") as f:
            json.dump({"location": weights, "file_length": len(blob), "initializers": entries}, f, indent=0)
    finally:
        shutil.rmtree(tmp)


def tiny_pth(manifest):
    picks = ["conv1_1.weight", "conv1_1.bias", "Mconv7_stage6_L2.weight", "Mconv7_stage6_L2.bias"]
    index = {e["name"]: k for k, e in enumerate(manifest)}
    sd = OrderedDict((n, torch.from_numpy(sw.tensor(index[n], n, manifest[index[n]]["shape"]))) for n in picks)
    torch.save(sd, os.path.join(OUT, "tiny_zip.pth"))
    torch.save(sd, os.path.join(OUT, "tiny_legacy.pth"), _use_new_zipfile_serialization=False)
    return [{"name": n, "tensor": index[n]} for n in picks]


def main():
    os.makedirs(OUT, exist_ok=True)
    torch.set_num_threads(max(1, os.cpu_count() or 1))
    img = cv2.imread(FRAME)  # BGR, as body.py receives it
    resized = util.smart_resize_k(img, fx=SCALE, fy=SCALE)
    padded, _pad = util.padRightDownCorner(resized, 8, 128)
    padded = np.ascontiguousarray(padded, dtype=np.uint8)
    padded.tofile(os.path.join(OUT, "input_bgr.bin"))
    h, w = padded.shape[:2]
    x = np.ascontiguousarray(np.transpose(np.float32(padded[:, :, :, np.newaxis]), (3, 2, 0, 1)) / 256 - 0.5)
    assert x.shape == (1, 3, h, w), x.shape

    cases = {"input": {"file": "input_bgr.bin", "height": h, "width": w}}

    # COCO-18: controlnet_aux's model class, exactly.
    coco = coco18_model()
    coco_manifest = manifest_of(coco, checkpoint_key)
    coco_sd = set_synthetic(coco, coco_manifest)
    with torch.no_grad():
        paf, heat = coco(torch.from_numpy(x))
    paf, heat = paf.numpy(), heat.numpy()
    np.concatenate([heat.ravel(), paf.ravel()]).astype("<f4").tofile(os.path.join(OUT, "coco18_torch.bin"))
    with open(os.path.join(OUT, "coco18_manifest.json"), "w") as f:
        json.dump(coco_manifest, f, indent=0)
    cases["coco18"] = {"output": "coco18_torch.bin", "heatmap_channels": heat.shape[1],
                       "paf_channels": paf.shape[1], "height": heat.shape[2], "width": heat.shape[3],
                       "tensors": len(coco_manifest)}
    write_onnx(coco, "coco18", ["paf", "heatmap"], coco_manifest, coco_sd, x, [paf, heat])
    cases["tiny_pth"] = tiny_pth(coco_manifest)

    # BODY_25: our torch module of the caffe architecture, single caffe-style output.
    b25 = Body25().eval()
    b25_manifest = manifest_of(b25, lambda k: k)
    b25_sd = set_synthetic(b25, b25_manifest)
    with torch.no_grad():
        out = b25(torch.from_numpy(x)).numpy()
    out.astype("<f4").tofile(os.path.join(OUT, "body25_torch.bin"))
    with open(os.path.join(OUT, "body25_manifest.json"), "w") as f:
        json.dump(b25_manifest, f, indent=0)
    cases["body25"] = {"output": "body25_torch.bin", "heatmap_channels": 26, "paf_channels": 52,
                       "height": out.shape[2], "width": out.shape[3], "tensors": len(b25_manifest)}
    write_onnx(b25, "body25", ["net_output"], b25_manifest, b25_sd, x, [out])

    with open(os.path.join(OUT, "cases.json"), "w") as f:
        json.dump(cases, f, indent=1)
    for name, v in (("coco18 heatmap", heat), ("coco18 paf", paf), ("body25", out)):
        print(f"{name}: max |x| {np.abs(v).max():.3g}, mean |x| {np.abs(v).mean():.3g}", file=sys.stderr)


if __name__ == "__main__":
    main()
