#!/usr/bin/env python3
"""Manifest of every tensor name and shape in the real SD 1.5 and sd-controlnet-canny
checkpoints (diffusers layout), from the models' configurations alone: the models
are instantiated on PyTorch's `meta` device, so no weights are allocated or downloaded.

Writes crates/gait-diffuse/tests/fixtures/sd15_manifest.json:
  {"unet": {name: shape}, "vae": {...}, "text_encoder": {...}, "controlnet": {...}}

Needs: torch==2.15.0 diffusers==0.42.1 transformers==5.23.0 (Python 3.11).
Regenerate: python tools/diffuse/make_manifest.py
"""

import json
import os

import torch
from diffusers import AutoencoderKL, ControlNetModel, UNet2DConditionModel
from transformers import CLIPTextConfig, CLIPTextModel

OUT = os.path.join(os.path.dirname(__file__), "..", "..", "crates", "gait-diffuse", "tests", "fixtures", "sd15_manifest.json")

# runwayml/stable-diffusion-v1-5 unet/config.json. Every value not listed is
# diffusers' UNet2DConditionModel default, which equals SD 1.5's:
# block_out_channels (320, 640, 1280, 1280), layers_per_block 2,
# down_block_types 3 x CrossAttnDownBlock2D + DownBlock2D, up_block_types
# UpBlock2D + 3 x CrossAttnUpBlock2D, attention_head_dim 8, norm_num_groups 32,
# in/out_channels 4, flip_sin_to_cos True, freq_shift 0.
UNET = dict(sample_size=64, cross_attention_dim=768)

# lllyasviel/sd-controlnet-canny config.json: ControlNetModel defaults
# (block_out_channels (320, 640, 1280, 1280), conditioning_embedding_out_channels
# (16, 32, 96, 256), attention_head_dim 8, layers_per_block 2) and:
CONTROLNET = dict(cross_attention_dim=768)

# runwayml/stable-diffusion-v1-5 vae/config.json.
VAE = dict(
    in_channels=3,
    out_channels=3,
    down_block_types=("DownEncoderBlock2D",) * 4,
    up_block_types=("UpDecoderBlock2D",) * 4,
    block_out_channels=(128, 256, 512, 512),
    layers_per_block=2,
    latent_channels=4,
    norm_num_groups=32,
    sample_size=512,
)

# runwayml/stable-diffusion-v1-5 text_encoder/config.json (openai/clip-vit-large-patch14's text tower).
TEXT = dict(
    vocab_size=49408,
    hidden_size=768,
    intermediate_size=3072,
    num_hidden_layers=12,
    num_attention_heads=12,
    max_position_embeddings=77,
    hidden_act="quick_gelu",
    projection_dim=768,
)


def shapes(model, prefix=""):
    # transformers 5 dropped the `text_model.` level of CLIPTextModel's state dict;
    # SD 1.5's text_encoder/model.safetensors (written by transformers 4) has it.
    return {(k if k.startswith(prefix) else prefix + k): list(v.shape) for k, v in sorted(model.state_dict().items())}


def main():
    with torch.device("meta"):
        manifest = {
            "unet": shapes(UNet2DConditionModel(**UNET)),
            "controlnet": shapes(ControlNetModel(**CONTROLNET)),
            "vae": shapes(AutoencoderKL(**VAE)),
            "text_encoder": shapes(CLIPTextModel(CLIPTextConfig(**TEXT)), "text_model."),
        }
    with open(OUT, "w") as f:
        json.dump(manifest, f, indent=0, sort_keys=True)
    print({k: len(v) for k, v in manifest.items()})


if __name__ == "__main__":
    main()
