#!/usr/bin/env python3
"""Exports controlnet_aux's HED network (ControlNetHED_Apache2) to ONNX for gait-edge's ort backend.

Needs: Python 3.11, `pip install torch==2.15.0 onnx==1.23.2 onnxscript` and `pip install controlnet-aux==0.0.10
--no-deps einops==0.8.2 huggingface_hub pillow opencv-python-headless numpy`.

    python3 tools/edge/export_hed_onnx.py ControlNetHED.pth ControlNetHED.onnx

Input `image`: [1, 3, H, W] float32 RGB in 0..255 (H, W multiples of 16); outputs `side1`..`side5`:
[1, 1, H / 2^k, W / 2^k] for k = 0..4, the raw (pre-sigmoid) side outputs.
"""

import sys
from pathlib import Path

import torch


def export_onnx(model: torch.nn.Module, path: Path) -> None:
    dummy = torch.zeros(1, 3, 64, 64)
    names = [f"side{i}" for i in range(1, 6)]
    dynamic = {"image": {2: "height", 3: "width"}}
    dynamic.update({n: {2: f"h{i}", 3: f"w{i}"} for i, n in enumerate(names, 1)})
    torch.onnx.export(
        model, (dummy,), str(path), input_names=["image"], output_names=names,
        dynamic_axes=dynamic, opset_version=17, dynamo=False,
    )


def main() -> None:
    src, dst = Path(sys.argv[1]), Path(sys.argv[2])
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from make_hed_fixtures import controlnet_aux_hed

    model = controlnet_aux_hed().ControlNetHED_Apache2()
    model.load_state_dict(torch.load(src, map_location="cpu"))
    export_onnx(model.float().eval(), dst)


if __name__ == "__main__":
    main()
