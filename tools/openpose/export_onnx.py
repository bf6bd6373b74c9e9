#!/usr/bin/env python3
"""Exports controlnet_aux's OpenPose COCO-18 body network (`body_pose_model.pth`) to ONNX for gait's ort backend.

Needs: Python 3.11 with torch (2.x, CPU is enough), controlnet-aux==0.0.10, onnx==1.23.2.
Usage (from the repository root):
    python tools/openpose/export_onnx.py body_pose_model.pth openpose_coco18.onnx
then in the pipeline config: `[pose]` with `kind = "openpose"`, `backend = "ort"`, `model_path = "openpose_coco18.onnx"`.

The graph has one input `image` (1x3xHxW, BGR, pixel/256 - 0.5, H and W dynamic, multiples of 8) and two outputs
`paf` (38 channels, stage-6 L1) and `heatmap` (19 channels, stage-6 L2), both at stride 8. The checkpoint's keys
are the model's state_dict keys without their first component (`conv1_1.weight` for `model0.conv1_1.weight`), the
same mapping controlnet_aux's `util.transfer` does.

BODY_25 has no PyTorch checkpoint: convert OpenPose's caffe model (pose/body_25) to ONNX with a caffe converter; its
single output (26 heatmaps then 52 PAFs, the caffe net's `net_output`) is what gait's ort backend expects with
`model = "body_25"`.

The fixture script (make_net_fixtures.py) uses `export` below on the same model class with synthetic weights.
"""
import argparse
import sys

import torch


def coco18_model():
    from controlnet_aux.open_pose.model import bodypose_model

    return bodypose_model().eval()


def checkpoint_key(state_dict_key: str) -> str:
    """controlnet_aux util.transfer: the checkpoint names a tensor without its first component."""
    return ".".join(state_dict_key.split(".")[1:])


def load_checkpoint(model, path):
    weights = torch.load(path, map_location="cpu", weights_only=True)
    model.load_state_dict({k: weights[checkpoint_key(k)] for k in model.state_dict().keys()})
    return model


def export(model, path, output_names, height=368, width=368, external_location=None):
    """torch.onnx (TorchScript exporter, opset 17), H and W dynamic. With `external_location`, every
    initializer goes into that file next to `path` (onnx external data)."""
    x = torch.zeros(1, 3, height, width)
    dyn = {"image": {2: "height", 3: "width"}}
    for n in output_names:
        dyn[n] = {2: "out_height", 3: "out_width"}
    torch.onnx.export(model, (x,), path, input_names=["image"], output_names=output_names, dynamic_axes=dyn,
                      opset_version=17, dynamo=False, do_constant_folding=True)
    if external_location is not None:
        import onnx

        m = onnx.load(path)
        onnx.save_model(m, path, save_as_external_data=True, all_tensors_to_one_file=True,
                        location=external_location, size_threshold=0, convert_attribute=False)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("checkpoint", help="body_pose_model.pth (lllyasviel/Annotators)")
    ap.add_argument("output", help="ONNX file to write")
    a = ap.parse_args()
    model = load_checkpoint(coco18_model(), a.checkpoint)
    with torch.no_grad():
        export(model, a.output, ["paf", "heatmap"])
    print(f"wrote {a.output}", file=sys.stderr)


if __name__ == "__main__":
    main()
