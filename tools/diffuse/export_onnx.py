#!/usr/bin/env python3
"""Exports SD 1.5 + a ControlNet from diffusers-layout folders to the four ONNX graphs that
gait-diffuse's ort backend (`backend = "ort"` in `[regenerator]`, kind "controlnet") runs.

Needs (Python 3.11): torch==2.15.0 diffusers==0.42.1 transformers==5.23.0 accelerate==1.15.0
safetensors==0.8.0 onnx==1.23.2 (onnxruntime==1.31.1 only for `--check`). The export uses
torch's TorchScript exporter (`dynamo=False`), opset 17.

    python tools/diffuse/export_onnx.py --sd MODELS/stable-diffusion-v1-5 \
        --controlnet MODELS/sd-controlnet-canny --out MODELS/onnx/sd15-controlnet-canny

The tiny test fixtures are regenerated with
    python tools/diffuse/export_onnx.py --sd crates/gait-diffuse/tests/fixtures/tiny \
        --controlnet crates/gait-diffuse/tests/fixtures/tiny/controlnet \
        --out crates/gait-diffuse/tests/fixtures/tiny_onnx --weights f16 --no-tokenizer
and the 9-channel inpainting UNet of make_modes_fixtures.py with
    python tools/diffuse/export_onnx.py --sd crates/gait-diffuse/tests/fixtures/tiny \
        --unet crates/gait-diffuse/tests/fixtures/tiny_inpaint_unet \
        --controlnet crates/gait-diffuse/tests/fixtures/tiny/controlnet \
        --out crates/gait-diffuse/tests/fixtures/tiny_onnx_inpaint --weights f16 --no-tokenizer --only unet

Layout written under --out (what the Rust side reads; `onnx_path` in the TOML, relative to the
models folder, default `onnx/sd15-controlnet-canny`):

  text_encoder/model.onnx  input_ids int64 [batch, sequence] -> last_hidden_state f32 [batch, sequence, dim]
  controlnet/model.onnx    sample f32 [batch, 4, h, w], timestep f32 [batch], encoder_hidden_states
                           f32 [batch, sequence, dim], controlnet_cond f32 [batch, 3, 8h, 8w] in [0, 1],
                           conditioning_scale f32 [] -> down_block_res_0 .. down_block_res_{N-1}
                           (N = 12 for SD 1.5), mid_block_res
  unet/model.onnx          sample, timestep, encoder_hidden_states, down_block_res_0 .. _{N-1},
                           mid_block_res -> noise_pred f32 [batch, 4, h, w]
  vae_decoder/model.onnx   latent_sample f32 [batch, 4, h, w] (already divided by the VAE's
                           scaling_factor) -> sample f32 [batch, 3, 8h, 8w] in [-1, 1]
  vae_encoder/model.onnx   sample f32 [batch, 3, 8h, 8w] in [-1, 1] -> latent_mean, latent_std
                           f32 [batch, 4, h, w] (the latent distribution, not scaled; only
                           image-to-image and inpainting need it)
  */config.json            the source folder's config.json (the Rust side reads the VAE's
                           scaling factor and the ControlNet's residual count from them)
  tokenizer/merges.txt     (and the other tokenizer files) copied from the SD folder, unless
                           --no-tokenizer

Batch, sequence and spatial axes are dynamic. A graph over 2 GB (SD 1.5's UNet in f32, 3.4 GB)
keeps its weights in `model.onnx_data` next to `model.onnx` (ONNX external data; keep the two
together). `--weights f16` stores the weights as f16 with a Cast to f32 in the graph (the
computation stays f32; exact when the weights are f16 already, as in the fixtures and in
SD 1.5's fp16 files), halving the files.
"""

import argparse
import os
import shutil
import tempfile

import numpy as np
import onnx
import torch
from onnx import helper, numpy_helper

OPSET = 17
# protobuf's hard limit is 2 GiB; stay clear of it.
EXTERNAL_DATA_BYTES = 1_800_000_000


class UnetWithResiduals(torch.nn.Module):
    """UNet2DConditionModel taking the ControlNet residuals as plain inputs."""

    def __init__(self, unet, n_down):
        super().__init__()
        self.unet, self.n_down = unet, n_down

    def forward(self, sample, timestep, encoder_hidden_states, *residuals):
        down, mid = residuals[: self.n_down], residuals[self.n_down]
        return self.unet(
            sample, timestep, encoder_hidden_states=encoder_hidden_states,
            down_block_additional_residuals=tuple(down), mid_block_additional_residual=mid,
            return_dict=False,
        )[0]


class ControlNetFlat(torch.nn.Module):
    """ControlNetModel returning its residuals as a flat tuple (down..., mid)."""

    def __init__(self, controlnet):
        super().__init__()
        self.controlnet = controlnet

    def forward(self, sample, timestep, encoder_hidden_states, controlnet_cond, conditioning_scale):
        down, mid = self.controlnet(
            sample, timestep, encoder_hidden_states=encoder_hidden_states,
            controlnet_cond=controlnet_cond, conditioning_scale=conditioning_scale, return_dict=False,
        )
        return (*down, mid)


class TextEncoder(torch.nn.Module):
    def __init__(self, text):
        super().__init__()
        self.text = text

    def forward(self, input_ids):
        return self.text(input_ids, return_dict=False)[0]


class VaeDecoder(torch.nn.Module):
    def __init__(self, vae):
        super().__init__()
        self.vae = vae

    def forward(self, latent_sample):
        return self.vae.decode(latent_sample, return_dict=False)[0]


class VaeEncoder(torch.nn.Module):
    def __init__(self, vae):
        super().__init__()
        self.vae = vae

    def forward(self, sample):
        dist = self.vae.encode(sample, return_dict=False)[0]
        return dist.mean, dist.std


def num_down_residuals(controlnet):
    return len(controlnet.controlnet_down_blocks)


def weights_to_f16(model):
    """Stores float32 initializers as float16 followed by a Cast back to float32."""
    graph = model.graph
    casts, keep = [], []
    for init in graph.initializer:
        if init.data_type != onnx.TensorProto.FLOAT or np.prod(init.dims, dtype=np.int64) < 16:
            keep.append(init)
            continue
        arr = numpy_helper.to_array(init)
        half = numpy_helper.from_array(arr.astype(np.float16), init.name + "_f16")
        keep.append(half)
        casts.append(helper.make_node("Cast", [half.name], [init.name], to=onnx.TensorProto.FLOAT,
                                      name=init.name + "_cast"))
    del graph.initializer[:]
    graph.initializer.extend(keep)
    nodes = list(graph.node)
    del graph.node[:]
    graph.node.extend(casts + nodes)
    return model


def save(module, args, names_in, names_out, dynamic, path, weights):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    tmp = tempfile.mkdtemp(prefix="gait-onnx-")
    try:
        raw = os.path.join(tmp, "model.onnx")
        with torch.no_grad():
            torch.onnx.export(
                module, args, raw, input_names=names_in, output_names=names_out,
                dynamic_axes=dynamic, opset_version=OPSET, dynamo=False, do_constant_folding=True,
            )
        model = onnx.load(raw)  # pulls in any external data the exporter split off
        if weights == "f16":
            model = weights_to_f16(model)
        size = sum(len(t.raw_data) for t in model.graph.initializer)
        for stale in (path, path + "_data"):
            if os.path.exists(stale):
                os.remove(stale)
        if size > EXTERNAL_DATA_BYTES:
            onnx.save_model(model, path, save_as_external_data=True, all_tensors_to_one_file=True,
                            location=os.path.basename(path) + "_data", size_threshold=1024)
        else:
            onnx.save_model(model, path)
    finally:
        shutil.rmtree(tmp)
    print(f"wrote {path} ({size / 1e6:.1f} MB of weights)", flush=True)


def copy_config(src_dir, dst_dir):
    src = os.path.join(src_dir, "config.json")
    if os.path.exists(src):
        os.makedirs(dst_dir, exist_ok=True)
        shutil.copy(src, os.path.join(dst_dir, "config.json"))


def export_text_encoder(sd, out, weights):
    from transformers import CLIPTextModel

    text = CLIPTextModel.from_pretrained(os.path.join(sd, "text_encoder"), torch_dtype=torch.float32).eval()
    ids = torch.zeros((1, 77), dtype=torch.int64)
    save(TextEncoder(text), (ids,), ["input_ids"], ["last_hidden_state"],
         {"input_ids": {0: "batch", 1: "sequence"}, "last_hidden_state": {0: "batch", 1: "sequence"}},
         os.path.join(out, "text_encoder", "model.onnx"), weights)
    copy_config(os.path.join(sd, "text_encoder"), os.path.join(out, "text_encoder"))


def denoiser_dummies(cross_dim, in_channels=4, latent=8):
    sample = torch.randn(2, in_channels, latent, latent)
    t = torch.full((2,), 501.0)
    ctx = torch.randn(2, 77, cross_dim)
    return sample, t, ctx


DENOISER_AXES = {
    "sample": {0: "batch", 2: "height", 3: "width"},
    "timestep": {0: "batch"},
    "encoder_hidden_states": {0: "batch", 1: "sequence"},
}


def export_controlnet(controlnet_dir, out, weights, controlnet=None):
    from diffusers import ControlNetModel

    if controlnet is None:
        controlnet = ControlNetModel.from_pretrained(controlnet_dir, torch_dtype=torch.float32)
    controlnet = controlnet.eval()
    n = num_down_residuals(controlnet)
    sample, t, ctx = denoiser_dummies(controlnet.config.cross_attention_dim, controlnet.config.in_channels)
    cond = torch.rand(2, controlnet.config.conditioning_channels, 64, 64)
    scale = torch.tensor(1.0)
    outs = [f"down_block_res_{i}" for i in range(n)] + ["mid_block_res"]
    axes = dict(DENOISER_AXES)
    axes["controlnet_cond"] = {0: "batch", 2: "image_height", 3: "image_width"}
    axes.update({o: {0: "batch", 2: f"{o}_height", 3: f"{o}_width"} for o in outs})
    save(ControlNetFlat(controlnet), (sample, t, ctx, cond, scale),
         ["sample", "timestep", "encoder_hidden_states", "controlnet_cond", "conditioning_scale"], outs,
         axes, os.path.join(out, "controlnet", "model.onnx"), weights)
    copy_config(controlnet_dir, os.path.join(out, "controlnet"))
    return n


def export_unet(unet_dir, out, weights, n_down, unet=None, controlnet=None):
    """The UNet with residual inputs; their shapes come from running `controlnet` (or a
    fresh one of the UNet's configuration) on the dummy inputs."""
    from diffusers import ControlNetModel, UNet2DConditionModel

    if unet is None:
        unet = UNet2DConditionModel.from_pretrained(unet_dir, torch_dtype=torch.float32)
    unet = unet.eval()
    sample, t, ctx = denoiser_dummies(unet.config.cross_attention_dim, unet.config.in_channels)
    with torch.no_grad():
        if controlnet is None:
            controlnet = ControlNetModel.from_unet(unet)
        # An inpainting UNet (9 channels) pairs with a 4-channel ControlNet,
        # which sees the latents only.
        down, mid = controlnet(sample[:, : controlnet.config.in_channels], t, encoder_hidden_states=ctx,
                               controlnet_cond=torch.rand(2, 3, 8 * sample.shape[2], 8 * sample.shape[3]),
                               return_dict=False)
    assert len(down) == n_down, (len(down), n_down)
    res = [f"down_block_res_{i}" for i in range(n_down)] + ["mid_block_res"]
    axes = dict(DENOISER_AXES)
    axes.update({r: {0: "batch", 2: f"{r}_height", 3: f"{r}_width"} for r in res})
    axes["noise_pred"] = {0: "batch", 2: "height", 3: "width"}
    save(UnetWithResiduals(unet, n_down), (sample, t, ctx, *down, mid),
         ["sample", "timestep", "encoder_hidden_states", *res], ["noise_pred"], axes,
         os.path.join(out, "unet", "model.onnx"), weights)
    copy_config(unet_dir, os.path.join(out, "unet"))


def export_vae_decoder(sd, out, weights):
    from diffusers import AutoencoderKL

    vae = AutoencoderKL.from_pretrained(os.path.join(sd, "vae"), torch_dtype=torch.float32).eval()
    lat = torch.randn(1, vae.config.latent_channels, 8, 8)
    save(VaeDecoder(vae), (lat,), ["latent_sample"], ["sample"],
         {"latent_sample": {0: "batch", 2: "height", 3: "width"},
          "sample": {0: "batch", 2: "image_height", 3: "image_width"}},
         os.path.join(out, "vae_decoder", "model.onnx"), weights)
    copy_config(os.path.join(sd, "vae"), os.path.join(out, "vae_decoder"))


def export_vae_encoder(sd, out, weights):
    from diffusers import AutoencoderKL

    vae = AutoencoderKL.from_pretrained(os.path.join(sd, "vae"), torch_dtype=torch.float32).eval()
    img = torch.rand(1, 3, 64, 64) * 2 - 1
    lat_axes = {0: "batch", 2: "height", 3: "width"}
    save(VaeEncoder(vae), (img,), ["sample"], ["latent_mean", "latent_std"],
         {"sample": {0: "batch", 2: "image_height", 3: "image_width"},
          "latent_mean": lat_axes, "latent_std": lat_axes},
         os.path.join(out, "vae_encoder", "model.onnx"), weights)
    copy_config(os.path.join(sd, "vae"), os.path.join(out, "vae_encoder"))


def copy_tokenizer(sd, out):
    src = os.path.join(sd, "tokenizer")
    dst = os.path.join(out, "tokenizer")
    os.makedirs(dst, exist_ok=True)
    for f in os.listdir(src):
        shutil.copy(os.path.join(src, f), os.path.join(dst, f))


COMPONENTS = ("text_encoder", "controlnet", "unet", "vae_decoder", "vae_encoder")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sd", required=True, help="SD 1.5 folder, diffusers layout")
    ap.add_argument("--controlnet", required=True, help="ControlNet folder, diffusers layout")
    ap.add_argument("--unet", help="UNet folder, diffusers layout (default: SD/unet), e.g. the "
                    "9-channel UNet of an inpainting checkpoint")
    ap.add_argument("--out", required=True)
    ap.add_argument("--weights", choices=("f32", "f16"), default="f32",
                    help="storage type of the weights (computation is f32 either way)")
    ap.add_argument("--only", default=",".join(COMPONENTS), help="comma-separated subset of " + ",".join(COMPONENTS))
    ap.add_argument("--no-tokenizer", action="store_true", help="do not copy tokenizer/")
    args = ap.parse_args()
    only = set(args.only.split(","))
    unknown = only - set(COMPONENTS)
    if unknown:
        ap.error(f"unknown components {sorted(unknown)}; valid: {', '.join(COMPONENTS)}")
    if "text_encoder" in only:
        export_text_encoder(args.sd, args.out, args.weights)
    if only & {"controlnet", "unet"}:
        from diffusers import ControlNetModel

        cn = ControlNetModel.from_pretrained(args.controlnet, torch_dtype=torch.float32)
        n = num_down_residuals(cn)
        if "controlnet" in only:
            export_controlnet(args.controlnet, args.out, args.weights, cn)
        if "unet" in only:
            export_unet(args.unet or os.path.join(args.sd, "unet"), args.out, args.weights, n, controlnet=cn)
    if "vae_decoder" in only:
        export_vae_decoder(args.sd, args.out, args.weights)
    if "vae_encoder" in only:
        export_vae_encoder(args.sd, args.out, args.weights)
    if not args.no_tokenizer:
        copy_tokenizer(args.sd, args.out)


if __name__ == "__main__":
    main()
