#!/usr/bin/env python3
"""HED fixtures for crates/gait-edge: controlnet_aux's own ControlNetHED_Apache2 with seeded random weights.

Needs: Python 3.11 and
    pip install torch==2.15.0 controlnet-aux==0.0.10 --no-deps
    pip install einops==0.8.2 huggingface_hub==2.4.0 pillow opencv-python-headless==4.12.0.88 numpy==2.4.6 \
        safetensors==0.7.0 onnx==1.23.2 onnxscript   # plus torch's own requirements
(controlnet_aux's package __init__ imports every annotator and needs torchvision/timm; this script
imports only its `hed` and `util` modules, so those are not needed.)
Regenerate from the repo root:  python3 tools/edge/make_hed_fixtures.py

The real checkpoint has 14.7 M float32 weights (59 MB), too big to commit. The fixture keeps the real
architecture, tensor names and shapes, but makes every conv weight sparse (a seeded random subset of
entries, scaled to keep activations alive), so the files gzip to a few hundred kB. Outputs in
crates/gait-edge/tests/fixtures/hed/:
- hed_random.pth.gz: torch.save(model.state_dict()), the format of ControlNetHED.pth, gzipped;
- hed_random.safetensors.gz: the same tensors as safetensors, gzipped;
- hed_random.onnx.gz: torch.onnx.export of the same model (tools/edge/export_hed_onnx.py), gzipped;
- input.png: a 64x64 RGB crop of a real frame (Sports2D demo video, BSD-3-Clause, (c) David Pagnon);
- expected.safetensors: `side1`..`side5` (the five side outputs, [1, 1, h, w] float32) from torch;
- annotator.png / annotator_safe.png: HEDdetector(...)(input, detect_resolution=64, image_resolution=64,
  safe=False/True, output_type="np")[..., 0], the full annotator (upsampling, sigmoid mean, safe step).
"""

import gzip
import importlib.util
import io
import sys
import types
from pathlib import Path

import cv2
import numpy as np
import torch
from safetensors.torch import save_file

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "crates/gait-edge/tests/fixtures/hed"
sys.path.insert(0, str(Path(__file__).resolve().parent))
from export_hed_onnx import export_onnx  # noqa: E402


def controlnet_aux_hed():
    """Imports controlnet_aux.hed without the package __init__ (which pulls every annotator)."""
    spec = importlib.util.find_spec("controlnet_aux")
    pkg = types.ModuleType("controlnet_aux")
    pkg.__path__ = list(spec.submodule_search_locations)
    sys.modules["controlnet_aux"] = pkg
    import controlnet_aux.hed as hed

    return hed


def sparse_random_(model: torch.nn.Module, seed: int = 20261122) -> None:
    g = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        for name, p in model.named_parameters():
            if name == "norm":
                p.copy_(torch.rand(p.shape, generator=g) * 255.0)
            elif name.endswith("bias"):
                p.copy_((torch.rand(p.shape, generator=g) - 0.5) * 0.2)
            else:
                n = p.numel()
                keep = min(n, max(4096, int(n * 0.002)))
                fan_in = n // p.shape[0]
                density = keep / n
                # Keep activations' scale: variance 2 / (fan_in * density) on the kept entries;
                # values rounded to 1/256 so the file compresses.
                std = (2.0 / (fan_in * density)) ** 0.5
                flat = torch.zeros(n)
                idx = torch.randperm(n, generator=g)[:keep]
                vals = torch.randn(keep, generator=g) * std
                flat[idx] = torch.round(vals * 256.0) / 256.0
                if name == "block1.convs.0.weight":
                    flat /= 255.0  # the first layer sees raw 0..255 pixels
                if "projection" in name:
                    flat *= 16.0  # side outputs of a few units, so the fused map spans 0..255
                p.copy_(flat.reshape(p.shape))


def gz(path: Path, data: bytes) -> None:
    with gzip.GzipFile(path, "wb", mtime=0) as f:
        f.write(data)


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    hed = controlnet_aux_hed()
    torch.manual_seed(0)
    model = hed.ControlNetHED_Apache2().float().eval()
    sparse_random_(model)
    state = model.state_dict()

    buf = io.BytesIO()
    torch.save(state, buf)
    gz(OUT / "hed_random.pth.gz", buf.getvalue())
    tmp = OUT / "tmp.safetensors"
    save_file({k: v.contiguous() for k, v in state.items()}, str(tmp))
    gz(OUT / "hed_random.safetensors.gz", tmp.read_bytes())
    tmp.unlink()
    onnx_tmp = OUT / "tmp.onnx"
    export_onnx(model, onnx_tmp)
    gz(OUT / "hed_random.onnx.gz", onnx_tmp.read_bytes())
    onnx_tmp.unlink()

    video = cv2.VideoCapture("/work/shared/data/sports2d-demo.mp4")
    video.set(cv2.CAP_PROP_POS_FRAMES, 170)
    ok, bgr = video.read()
    assert ok
    crop = cv2.resize(bgr[420:740, 900:1220], (64, 64), interpolation=cv2.INTER_AREA)
    rgb = cv2.cvtColor(crop, cv2.COLOR_BGR2RGB)
    assert cv2.imwrite(str(OUT / "input.png"), crop)

    with torch.no_grad():
        x = torch.from_numpy(rgb.copy()).float().permute(2, 0, 1)[None]
        sides = model(x)
    save_file({f"side{i + 1}": s.contiguous() for i, s in enumerate(sides)}, str(OUT / "expected.safetensors"))
    for i, s in enumerate(sides):
        print(f"side{i + 1}: shape {tuple(s.shape)}, min {s.min():.4g}, max {s.max():.4g}, std {s.std():.4g}")

    det = hed.HEDdetector(model)
    for name, safe in [("annotator.png", False), ("annotator_safe.png", True)]:
        out = det(rgb, detect_resolution=64, image_resolution=64, safe=safe, output_type="np")
        assert cv2.imwrite(str(OUT / name), out[..., 0])
        print(f"{name}: min {out.min()}, max {out.max()}, mean {out.mean():.2f}")
    print(f"torch {torch.__version__}; wrote {OUT}")


if __name__ == "__main__":
    main()
