#!/usr/bin/env python3
"""Fixtures for gait-diffuse: tiny random diffusers models and their outputs.

Runs the reference implementation (diffusers + transformers + torch, CPU) on tiny
random configurations of the SD 1.5 + ControlNet models and writes, under
crates/gait-diffuse/tests/fixtures/:

  tiny/{unet,controlnet,vae,text_encoder}/  config.json + weights (f16 safetensors,
                                            diffusers / transformers layout)
  tiny/tokenizer/merges.txt                  the real CLIP BPE merges (SD 1.5's file)
  tokenizer_cases.json                       CLIPTokenizer ids for sample strings
  expected.safetensors                       inputs and reference outputs (f32)

Weights are drawn in f32, rounded to f16 and used as f32 by the reference, so the
f16 files hold exactly the weights the reference ran with.

Needs (Python 3.11): torch==2.15.0 diffusers==0.42.1 transformers==5.23.0
accelerate==1.15.0 safetensors==0.8.0 pillow, and the CLIP vocabulary
`open_clip/bpe_simple_vocab_16e6.txt.gz` from the wheel open_clip_torch==3.3.0
(`pip download --no-deps open_clip_torch==3.3.0`, unzip that one file). PyPI torch
pulls its CUDA packages (~3 GB); `pip install torch` in full was what imported on CPU.
Regenerate:
  python tools/diffuse/make_fixtures.py --bpe /path/to/bpe_simple_vocab_16e6.txt.gz
"""

import argparse
import gzip
import json
import os

import numpy as np
import torch
from diffusers import (
    AutoencoderKL,
    ControlNetModel,
    DDIMScheduler,
    StableDiffusionControlNetPipeline,
    UNet2DConditionModel,
    UniPCMultistepScheduler,
)
from PIL import Image
from safetensors.torch import save_file
from transformers import CLIPTextConfig, CLIPTextModel, CLIPTokenizer

OUT = os.path.join(os.path.dirname(__file__), "..", "..", "crates", "gait-diffuse", "tests", "fixtures")

PROMPT = "an able-body person walking, intact lower limbs, 2 legs, full-body portrait, realistic"
NEGATIVE = "cyborg, amputee, panfuturism"

# Tiny sizes: 64x64 images, latents 8x8 (VAE factor 8 as in SD 1.5).
CROSS = 8  # text hidden size = UNet cross-attention dim
UNET_KW = dict(
    sample_size=8,
    in_channels=4,
    out_channels=4,
    block_out_channels=(32, 64),
    layers_per_block=1,
    down_block_types=("CrossAttnDownBlock2D", "DownBlock2D"),
    up_block_types=("UpBlock2D", "CrossAttnUpBlock2D"),
    cross_attention_dim=CROSS,
    attention_head_dim=2,
    # SD's group count (the fixtures predate our own UNet, which takes any count;
    # kept so the committed tiny weights and ONNX exports stay as they are).
    norm_num_groups=32,
)
CONTROLNET_KW = dict(
    in_channels=4,
    block_out_channels=(32, 64),
    layers_per_block=1,
    down_block_types=("CrossAttnDownBlock2D", "DownBlock2D"),
    cross_attention_dim=CROSS,
    attention_head_dim=2,
    norm_num_groups=32,
    conditioning_embedding_out_channels=(4, 8, 8, 16),
)
VAE_KW = dict(
    in_channels=3,
    out_channels=3,
    down_block_types=("DownEncoderBlock2D",) * 4,
    up_block_types=("UpDecoderBlock2D",) * 4,
    block_out_channels=(8, 16, 16, 16),
    layers_per_block=1,
    latent_channels=4,
    norm_num_groups=4,
    sample_size=64,
)
TEXT_KW = dict(
    vocab_size=49408,
    hidden_size=CROSS,
    intermediate_size=16,
    num_hidden_layers=2,
    num_attention_heads=2,
    max_position_embeddings=77,
    hidden_act="quick_gelu",
    bos_token_id=49406,
    eos_token_id=49407,
    pad_token_id=1,
)
# SD 1.5's scheduler config (scheduler/scheduler_config.json of the SD 1.5 repo).
SCHED_KW = dict(
    beta_start=0.00085,
    beta_end=0.012,
    beta_schedule="scaled_linear",
    num_train_timesteps=1000,
    clip_sample=False,
    set_alpha_to_one=False,
    steps_offset=1,
)


def randomize(model, seed):
    """Replaces every parameter by a seeded random value rounded to f16."""
    g = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        for name, p in sorted(model.named_parameters()):
            if p.dim() > 1:
                v = torch.randn(p.shape, generator=g) / np.sqrt(p[0].numel())
            elif "norm" in name and name.endswith("weight"):
                v = 1.0 + 0.1 * torch.randn(p.shape, generator=g)
            else:
                v = 0.1 * torch.randn(p.shape, generator=g)
            p.copy_(v.half().float())
    return model.eval()


def save_weights(model, folder, filename):
    os.makedirs(folder, exist_ok=True)
    sd = {k: v.detach().half().contiguous() for k, v in model.state_dict().items()}
    save_file(sd, os.path.join(folder, filename))


def bytes_to_unicode():
    bs = list(range(ord("!"), ord("~") + 1)) + list(range(ord("¡"), ord("¬") + 1)) + list(range(ord("®"), ord("ÿ") + 1))
    cs = bs[:]
    n = 0
    for b in range(256):
        if b not in bs:
            bs.append(b)
            cs.append(256 + n)
            n += 1
    return dict(zip(bs, [chr(c) for c in cs]))


def write_tokenizer(bpe_path, folder):
    """SD 1.5's tokenizer files, built from the CLIP BPE list as OpenAI's CLIP does."""
    lines = gzip.open(bpe_path).read().decode("utf-8").split("\n")
    merges = lines[1 : 49152 - 256 - 2 + 1]
    vocab = list(bytes_to_unicode().values())
    vocab = vocab + [v + "</w>" for v in vocab]
    vocab += ["".join(m.split()) for m in merges]
    vocab += ["<|startoftext|>", "<|endoftext|>"]
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "merges.txt"), "w", encoding="utf-8") as f:
        f.write("#version: 0.2\n" + "\n".join(merges) + "\n")
    tmp_vocab = os.path.join("/tmp", "gait_diffuse_vocab.json")
    with open(tmp_vocab, "w", encoding="utf-8") as f:
        json.dump({t: i for i, t in enumerate(vocab)}, f)
    tok = CLIPTokenizer(tmp_vocab, os.path.join(folder, "merges.txt"), pad_token="<|endoftext|>")
    tok.model_max_length = 77
    return tok


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bpe", required=True)
    args = ap.parse_args()
    torch.manual_seed(0)
    tiny = os.path.join(OUT, "tiny")

    tok = write_tokenizer(args.bpe, os.path.join(tiny, "tokenizer"))
    cases = [
        PROMPT,
        NEGATIVE,
        "",
        "A  PHOTO of   3 people's legs!!",
        "hello-world, it's 2026; tea & coffee?",
        "unbelievable misunderstanding antidisestablishmentarianism",
        " ".join(["walking"] * 90),
    ]
    tok_out = [
        {"text": t, "ids": tok(t, padding="max_length", max_length=77, truncation=True).input_ids} for t in cases
    ]
    with open(os.path.join(OUT, "tokenizer_cases.json"), "w") as f:
        json.dump(tok_out, f, indent=0)

    unet = randomize(UNet2DConditionModel(**UNET_KW), 1)
    controlnet = randomize(ControlNetModel(**CONTROLNET_KW), 2)
    vae = randomize(AutoencoderKL(**VAE_KW), 3)
    text = randomize(CLIPTextModel(CLIPTextConfig(**TEXT_KW)), 4)
    for name, m in [("unet", unet), ("controlnet", controlnet), ("vae", vae)]:
        save_weights(m, os.path.join(tiny, name), "diffusion_pytorch_model.safetensors")
        m.save_config(os.path.join(tiny, name))
    save_weights(text, os.path.join(tiny, "text_encoder"), "model.safetensors")
    text.config.save_pretrained(os.path.join(tiny, "text_encoder"))

    exp = {}
    g = torch.Generator().manual_seed(10)
    with torch.no_grad():
        ids = torch.tensor([tok_out[0]["ids"], tok_out[1]["ids"]])
        exp["text.input_ids"] = ids.to(torch.int64)
        exp["text.hidden"] = text(ids)[0]

        sample = torch.randn((2, 4, 8, 8), generator=g)
        ctx = torch.randn((2, 77, CROSS), generator=g)
        cond = torch.rand((2, 3, 64, 64), generator=g)
        t = 501
        exp["cn.sample"], exp["cn.ctx"], exp["cn.cond"] = sample, ctx, cond
        exp["cn.t"] = torch.tensor([float(t)])
        down, mid = controlnet(sample, t, encoder_hidden_states=ctx, controlnet_cond=cond, conditioning_scale=0.7, return_dict=False)
        for i, d in enumerate(down):
            exp[f"cn.down.{i}"] = d
        exp["cn.mid"] = mid
        exp["unet.out"] = unet(sample, t, encoder_hidden_states=ctx, down_block_additional_residuals=down, mid_block_additional_residual=mid).sample
        exp["unet.plain"] = unet(sample, t, encoder_hidden_states=ctx).sample

        lat = torch.randn((1, 4, 8, 8), generator=g)
        exp["vae.latents"] = lat
        exp["vae.decoded"] = vae.decode(lat).sample
        img = torch.rand((1, 3, 64, 64), generator=g) * 2 - 1
        exp["vae.image"] = img
        exp["vae.encoded_mean"] = vae.encode(img).latent_dist.mean

        # Schedulers: timesteps for 10 and 20 steps, and 4 chained steps on fixed model outputs.
        x0 = torch.randn((1, 4, 8, 8), generator=g)
        outs = torch.randn((4, 1, 4, 8, 8), generator=g)
        exp["sched.x0"], exp["sched.eps"] = x0, outs
        for name, cls in [("ddim", DDIMScheduler), ("unipc", UniPCMultistepScheduler)]:
            s = cls.from_config(SCHED_KW)
            for n in (2, 10, 20):
                s.set_timesteps(n)
                exp[f"sched.{name}.timesteps.{n}"] = s.timesteps.to(torch.int64)
            s = cls.from_config(SCHED_KW)
            s.set_timesteps(4)
            x = x0.clone()
            for i, ts in enumerate(s.timesteps):
                x = s.step(outs[i], ts, x).prev_sample
                exp[f"sched.{name}.step.{i}"] = x.clone()
            s = cls.from_config(SCHED_KW)
            s.set_timesteps(10)
            noise = outs[0]
            exp[f"sched.{name}.add_noise"] = s.add_noise(x0, noise, torch.tensor([s.timesteps[3]]))

    # The complete pipeline: 2 steps, guidance on, fixed initial latents, 64x64.
    edge = (torch.rand((64, 64), generator=g) > 0.8).to(torch.uint8) * 255
    exp["pipe.edge"] = edge
    control = Image.fromarray(edge.numpy()).convert("RGB")
    latents = torch.randn((1, 4, 8, 8), generator=g)
    exp["pipe.latents"] = latents
    for name, cls in [("ddim", DDIMScheduler), ("unipc", UniPCMultistepScheduler)]:
        pipe = StableDiffusionControlNetPipeline(
            vae=vae,
            text_encoder=text,
            tokenizer=tok,
            unet=unet,
            controlnet=controlnet,
            scheduler=cls.from_config(SCHED_KW),
            safety_checker=None,
            feature_extractor=None,
            requires_safety_checker=False,
        )
        pipe.set_progress_bar_config(disable=True)
        out = pipe(
            PROMPT,
            image=control,
            negative_prompt=NEGATIVE,
            num_inference_steps=2,
            guidance_scale=7.5,
            controlnet_conditioning_scale=0.8,
            latents=latents.clone(),
            height=64,
            width=64,
            output_type="np",
        ).images
        exp[f"pipe.{name}.image"] = torch.from_numpy(out).permute(0, 3, 1, 2).contiguous()

    exp = {k: (v.float() if v.dtype != torch.int64 else v).contiguous() for k, v in exp.items()}
    save_file(exp, os.path.join(OUT, "expected.safetensors"))
    print("wrote", OUT)


if __name__ == "__main__":
    main()
