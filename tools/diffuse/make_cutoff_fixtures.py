#!/usr/bin/env python3
"""Fixtures for gait-diffuse's speed settings (issue 20): DPM-Solver++ 2M, the
classifier-free-guidance cut-off and the ControlNet's control_guidance_start / end.

Runs stock diffusers pipelines (StableDiffusionControlNetPipeline, ...Img2ImgPipeline and
...InpaintPipeline, 4-channel UNet) on the tiny random models of make_fixtures.py under
crates/gait-diffuse/tests/fixtures/tiny/, with the frame, edge map, mask and noise of
modes.safetensors (make_modes_fixtures.py), and writes

  crates/gait-diffuse/tests/fixtures/cutoffs.json           the cases and their settings
  crates/gait-diffuse/tests/fixtures/cutoffs.safetensors    cut.<case>.image (1, 3, 64, 64) in [0, 1]

The CFG cut-off is diffusers' SDCFGCutoffCallback (cutoff_step_ratio = guidance_end): after
the step it fires on, guidance is off and the prompt embeddings keep their conditional row.
A ControlNet pipeline also holds its control image twice (one per guidance row), so the
callback here also keeps the conditional control image, as diffusers'
SDXLControlnetCFGCutoffCallback does for SDXL. DPM-Solver++ 2M is DPMSolverMultistepScheduler
with its defaults (dpmsolver++, order 2, midpoint, final sigma 0) on SD 1.5's config.

Needs the packages of make_modes_fixtures.py. Regenerate (after make_fixtures.py and
make_modes_fixtures.py):
  python tools/diffuse/make_cutoff_fixtures.py
"""

import json
import os

import torch
from diffusers import (
    DDIMScheduler,
    DPMSolverMultistepScheduler,
    StableDiffusionControlNetImg2ImgPipeline,
    StableDiffusionControlNetInpaintPipeline,
    StableDiffusionControlNetPipeline,
    UniPCMultistepScheduler,
)
from diffusers.models.autoencoders import vae as vae_module
from diffusers.pipelines.controlnet import pipeline_controlnet_img2img, pipeline_controlnet_inpaint
from PIL import Image
from safetensors.torch import load_file, save_file

from cfg_cutoff import cutoff_kwargs
from make_fixtures import SCHED_KW
from make_modes_fixtures import COND_SCALE, GUIDANCE, FIX, fixed, load_tiny

SCHEDULERS = {"ddim": DDIMScheduler, "unipc": UniPCMultistepScheduler, "dpmpp2m": DPMSolverMultistepScheduler}

# name, mode, scheduler, steps, strength, guidance_end, control_guidance_start, control_guidance_end
CASES = [
    ("t2i_dpmpp2m", "text2img", "dpmpp2m", 6, 1.0, 1.0, 0.0, 1.0),
    ("t2i_cfg_unipc", "text2img", "unipc", 6, 1.0, 0.4, 0.0, 1.0),
    ("t2i_control_ddim", "text2img", "ddim", 6, 1.0, 1.0, 0.2, 0.7),
    ("t2i_all_dpmpp2m", "text2img", "dpmpp2m", 8, 1.0, 0.5, 0.1, 0.6),
    ("img2img_all_dpmpp2m", "img2img", "dpmpp2m", 8, 0.75, 0.5, 0.1, 0.6),
    ("inpaint_all_unipc", "inpaint", "unipc", 8, 0.75, 0.5, 0.1, 0.6),
]


def main():
    unet, controlnet, vae, text, pos, neg = load_tiny()
    m = load_file(os.path.join(FIX, "modes.safetensors"))
    frame = Image.fromarray(m["modes.frame"].to(torch.uint8).numpy())
    control = Image.fromarray(m["modes.edge"].to(torch.uint8).numpy()).convert("RGB")
    mask = Image.fromarray(m["modes.mask"].to(torch.uint8).numpy())
    noise, enc_eps = m["modes.noise"], m["modes.enc_eps"]
    vae_module.randn_tensor = fixed(enc_eps, "VAE latent sample")
    pipeline_controlnet_img2img.randn_tensor = fixed(noise, "img2img noise")
    pipeline_controlnet_inpaint.randn_tensor = fixed(noise, "inpaint noise")

    parts = dict(vae=vae, text_encoder=text, tokenizer=None, unet=unet, controlnet=controlnet,
                 safety_checker=None, feature_extractor=None, requires_safety_checker=False)
    exp, listed = {}, []
    for name, mode, sched, steps, strength, g_end, c_start, c_end in CASES:
        call = dict(prompt_embeds=pos, negative_prompt_embeds=neg, num_inference_steps=steps,
                    guidance_scale=GUIDANCE, controlnet_conditioning_scale=COND_SCALE,
                    control_guidance_start=c_start, control_guidance_end=c_end,
                    height=64, width=64, output_type="np")
        scheduler = SCHEDULERS[sched].from_config(SCHED_KW)
        if mode == "text2img":
            pipe = StableDiffusionControlNetPipeline(scheduler=scheduler, **parts)
            args = dict(image=control, latents=noise.clone())
            halves = ["image"]
        elif mode == "img2img":
            pipe = StableDiffusionControlNetImg2ImgPipeline(scheduler=scheduler, **parts)
            args = dict(image=frame, control_image=control, strength=strength)
            halves = ["control_image"]
        else:
            pipe = StableDiffusionControlNetInpaintPipeline(scheduler=scheduler, **parts)
            args = dict(image=frame, mask_image=mask, control_image=control, strength=strength)
            halves = ["control_image", "mask", "masked_image_latents"]
        args.update(cutoff_kwargs(g_end, halves))
        pipe.set_progress_bar_config(disable=True)
        out = pipe(**call, **args).images
        exp[f"cut.{name}.image"] = torch.from_numpy(out).permute(0, 3, 1, 2).float().contiguous()
        listed.append(dict(name=name, mode=mode, scheduler=sched, steps=steps, strength=strength,
                           guidance_scale=GUIDANCE, conditioning_scale=COND_SCALE, guidance_end=g_end,
                           control_guidance_start=c_start, control_guidance_end=c_end))
    save_file(exp, os.path.join(FIX, "cutoffs.safetensors"))
    with open(os.path.join(FIX, "cutoffs.json"), "w") as f:
        json.dump(listed, f, indent=1)
    print("wrote", os.path.join(FIX, "cutoffs.safetensors"))


if __name__ == "__main__":
    main()
