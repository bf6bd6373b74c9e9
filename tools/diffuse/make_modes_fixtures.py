#!/usr/bin/env python3
"""Fixtures for gait-diffuse's image-to-image and inpainting modes.

Runs diffusers' StableDiffusionControlNetImg2ImgPipeline and
StableDiffusionControlNetInpaintPipeline (4-channel UNet, as SD 1.5) on the tiny
random models that tools/diffuse/make_fixtures.py wrote under
crates/gait-diffuse/tests/fixtures/tiny/, and writes
crates/gait-diffuse/tests/fixtures/modes.safetensors (f32):

  modes.frame        (64, 64, 3)  the RGB frame, uint8 values
  modes.init         (1, 3, 64, 64) diffusers' preprocessed frame in [-1, 1]
  modes.edge         (64, 64)     the edge map, uint8 values
  modes.mask         (64, 64)     the inpainting mask, uint8 values (white = regenerate)
  modes.noise        (1, 4, 8, 8) the noise both pipelines add to the image latents
  modes.enc_eps      (1, 4, 8, 8) the standard normals the VAE's latent sample uses
  modes.enc_mean/std (1, 4, 8, 8) vae.encode(init).latent_dist mean and std
  modes.{img2img,inpaint}.{ddim,unipc}.image  (1, 3, 64, 64) output images in [0, 1]
  modes.inpaint_full.unipc.image              the same at strength 1 (pure-noise start)
  modes.inpaint9.ddim.image, modes.inpaint9_full.unipc.image
                     the same two runs with a 9-channel inpainting UNet (as
                     runwayml/stable-diffusion-inpainting: latents, mask and masked-image
                     latents concatenated), written to crates/gait-diffuse/tests/fixtures/
                     tiny_inpaint_unet/ (random, seeded, f16 like the other tiny models)

Stock diffusers throughout: the candle and ort tests both compare with these images.

Both pipelines draw their randomness through `randn_tensor`; the script replaces it
(in the two pipeline modules and in the VAE's DiagonalGaussianDistribution) by
functions that return the fixed tensors above, so the Rust side can use the same
noise. The prompt embeddings come from the committed CLIP ids in
tokenizer_cases.json (the paper's prompt and negative prompt), so no vocabulary is
needed here. 3 scheduler steps at strength 0.75: diffusers runs the last 2.

Needs (Python 3.11): torch==2.15.0 diffusers==0.42.1 transformers==5.23.0
accelerate==1.15.0 safetensors==0.8.0 pillow numpy.
Regenerate (after make_fixtures.py):
  python tools/diffuse/make_modes_fixtures.py
"""

import json
import os

import numpy as np
import torch
from diffusers import (
    AutoencoderKL,
    ControlNetModel,
    DDIMScheduler,
    StableDiffusionControlNetImg2ImgPipeline,
    StableDiffusionControlNetInpaintPipeline,
    UNet2DConditionModel,
    UniPCMultistepScheduler,
)
from diffusers.models.autoencoders import vae as vae_module
from diffusers.pipelines.controlnet import pipeline_controlnet_img2img, pipeline_controlnet_inpaint
from PIL import Image
from safetensors.torch import save_file
from transformers import CLIPTextModel

# SD 1.5's scheduler config (this script runs from its own folder, so the sibling imports).
from make_fixtures import SCHED_KW, UNET_KW, randomize, save_weights

FIX = os.path.join(os.path.dirname(__file__), "..", "..", "crates", "gait-diffuse", "tests", "fixtures")
TINY = os.path.join(FIX, "tiny")
INPAINT_UNET = os.path.join(FIX, "tiny_inpaint_unet")
STEPS, STRENGTH, GUIDANCE, COND_SCALE = 3, 0.75, 7.5, 0.8


def fixed(t, what):
    """A stand-in for randn_tensor that returns `t` (checking the shape asked for)."""

    def randn_tensor(shape, generator=None, device=None, dtype=None, layout=None):
        assert tuple(shape) == tuple(t.shape), f"{what}: asked for {tuple(shape)}"
        return t.clone().to(dtype=dtype or t.dtype)

    return randn_tensor


def load_tiny():
    """The tiny models in f32 and the paper's prompt and negative prompt embeddings (from the
    committed CLIP ids of tokenizer_cases.json)."""
    f32 = torch.float32
    unet = UNet2DConditionModel.from_pretrained(os.path.join(TINY, "unet"), torch_dtype=f32).eval()
    controlnet = ControlNetModel.from_pretrained(os.path.join(TINY, "controlnet"), torch_dtype=f32).eval()
    vae = AutoencoderKL.from_pretrained(os.path.join(TINY, "vae"), torch_dtype=f32).eval()
    text = CLIPTextModel.from_pretrained(os.path.join(TINY, "text_encoder"), torch_dtype=f32).eval()
    with open(os.path.join(FIX, "tokenizer_cases.json")) as f:
        cases = json.load(f)
    with torch.no_grad():
        pos = text(torch.tensor([cases[0]["ids"]]))[0]
        neg = text(torch.tensor([cases[1]["ids"]]))[0]
    return unet, controlnet, vae, text, pos, neg


def main():
    unet, controlnet, vae, text, pos, neg = load_tiny()

    g = torch.Generator().manual_seed(20)
    exp = {}
    # A frame with some structure (smooth gradients plus noise), an edge map, a leg-like mask.
    yy, xx = torch.meshgrid(torch.arange(64.0), torch.arange(64.0), indexing="ij")
    frame = torch.stack([xx * 4, yy * 4, (xx + yy) * 2], -1) + 40 * torch.rand((64, 64, 3), generator=g)
    frame = frame.clamp(0, 255).round().to(torch.uint8)
    edge = (torch.rand((64, 64), generator=g) > 0.8).to(torch.uint8) * 255
    mask = torch.zeros((64, 64), dtype=torch.uint8)
    mask[30:62, 18:30] = 255
    mask[34:60, 36:47] = 255
    mask[40:44, 30:36] = 200  # grey: binarized to 1 by diffusers (>= 0.5)
    mask[20:24, 20:28] = 100  # grey: binarized to 0
    noise = torch.randn((1, 4, 8, 8), generator=g)
    enc_eps = torch.randn((1, 4, 8, 8), generator=g)
    exp.update({"modes.frame": frame, "modes.edge": edge, "modes.mask": mask, "modes.noise": noise, "modes.enc_eps": enc_eps})

    frame_pil = Image.fromarray(frame.numpy())
    control = Image.fromarray(edge.numpy()).convert("RGB")
    mask_pil = Image.fromarray(mask.numpy())

    init = (torch.from_numpy(np.asarray(frame_pil, dtype=np.float32) / 255.0).permute(2, 0, 1)[None] * 2 - 1)
    exp["modes.init"] = init
    with torch.no_grad():
        dist = vae.encode(init).latent_dist
        exp["modes.enc_mean"], exp["modes.enc_std"] = dist.mean, dist.std

    vae_module.randn_tensor = fixed(enc_eps, "VAE latent sample")
    pipeline_controlnet_img2img.randn_tensor = fixed(noise, "img2img noise")
    pipeline_controlnet_inpaint.randn_tensor = fixed(noise, "inpaint noise")

    common = dict(
        vae=vae, text_encoder=text, tokenizer=None, unet=unet, controlnet=controlnet,
        safety_checker=None, feature_extractor=None, requires_safety_checker=False,
    )
    call = dict(
        prompt_embeds=pos, negative_prompt_embeds=neg, num_inference_steps=STEPS,
        guidance_scale=GUIDANCE, controlnet_conditioning_scale=COND_SCALE,
        height=64, width=64, output_type="np", generator=torch.Generator().manual_seed(0),
    )
    run_all(exp, "modes", common, call, frame_pil, control, mask_pil)

    unet9 = randomize(UNet2DConditionModel(**{**UNET_KW, "in_channels": 9}), 5)
    save_weights(unet9, INPAINT_UNET, "diffusion_pytorch_model.safetensors")
    unet9.save_config(INPAINT_UNET)
    run_inpaint9(exp, {**common, "unet": unet9}, call, frame_pil, control, mask_pil)

    exp = {k: v.float().contiguous() for k, v in exp.items()}
    save_file(exp, os.path.join(FIX, "modes.safetensors"))
    print("wrote", os.path.join(FIX, "modes.safetensors"))


def run_all(exp, prefix, common, call, frame_pil, control, mask_pil):
    for name, cls in [("ddim", DDIMScheduler), ("unipc", UniPCMultistepScheduler)]:
        pipe = StableDiffusionControlNetImg2ImgPipeline(scheduler=cls.from_config(SCHED_KW), **common)
        pipe.set_progress_bar_config(disable=True)
        out = pipe(image=frame_pil, control_image=control, strength=STRENGTH, **call).images
        exp[f"{prefix}.img2img.{name}.image"] = torch.from_numpy(out).permute(0, 3, 1, 2)

        pipe = StableDiffusionControlNetInpaintPipeline(scheduler=cls.from_config(SCHED_KW), **common)
        pipe.set_progress_bar_config(disable=True)
        out = pipe(image=frame_pil, mask_image=mask_pil, control_image=control, strength=STRENGTH, **call).images
        exp[f"{prefix}.inpaint.{name}.image"] = torch.from_numpy(out).permute(0, 3, 1, 2)
        if name == "unipc":
            out = pipe(image=frame_pil, mask_image=mask_pil, control_image=control, strength=1.0, **call).images
            exp[f"{prefix}.inpaint_full.unipc.image"] = torch.from_numpy(out).permute(0, 3, 1, 2)


def run_inpaint9(exp, common, call, frame_pil, control, mask_pil):
    for name, cls, strength, key in [
        ("ddim", DDIMScheduler, STRENGTH, "modes.inpaint9.ddim.image"),
        ("unipc", UniPCMultistepScheduler, 1.0, "modes.inpaint9_full.unipc.image"),
    ]:
        pipe = StableDiffusionControlNetInpaintPipeline(scheduler=cls.from_config(SCHED_KW), **common)
        pipe.set_progress_bar_config(disable=True)
        out = pipe(image=frame_pil, mask_image=mask_pil, control_image=control, strength=strength, **call).images
        exp[key] = torch.from_numpy(out).permute(0, 3, 1, 2)


if __name__ == "__main__":
    main()
