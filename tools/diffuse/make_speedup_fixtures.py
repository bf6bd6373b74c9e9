#!/usr/bin/env python3
"""Fixtures for gait-diffuse's UNet speed-ups: DeepCache and token merging (ToMe).

Runs the stock reference implementations, DeepCache's DeepCacheSDHelper (PyPI deepcache 0.1.1)
and tomesd.apply_patch (PyPI tomesd 0.1.3), on stock diffusers ControlNet pipelines
(StableDiffusionControlNetPipeline and ...Img2ImgPipeline) with the tiny random models of
make_fixtures.py under crates/gait-diffuse/tests/fixtures/tiny/ and the frame, edge map and
noise of modes.safetensors (make_modes_fixtures.py), and writes

  crates/gait-diffuse/tests/fixtures/speedups.json          the cases and their settings
  crates/gait-diffuse/tests/fixtures/speedups.safetensors   (f32)
      <case>.image  (1, 3, H, W) the output image in [0, 1]
      <case>.noise  (1, 4, H/8, W/8) the initial latents, for the cases that are not 64x64
      <case>.edge   (H, W) the edge map (uint8 values), for the cases that are not 64x64
      <case>.start  (1, 4, 8, 8) the start latents of the init = "previous" cases (below)

A case's settings: mode, scheduler, steps, strength (img2img), guidance_end (the CFG cut-off of
cfg_cutoff.py), control_start / control_end (control_guidance_start / end), cache_interval and
cache_branch (DeepCacheSDHelper.set_params' cache_interval and cache_branch_id; interval 1 = no
DeepCache), token_merge_ratio (tomesd's ratio; 0 = no ToMe), merge_seed (below), height, width,
init ("noise" or "previous", below); also guidance_scale and conditioning_scale (GUIDANCE and
COND_SCALE of make_modes_fixtures.py).

A case's "init" is "noise" (the first 12 cases: text2img from the noise, or img2img of the
modes frame) or "previous" (the last cases, PREV_CASES; this project's init = "previous",
where frame t starts from frame t-1's final latents noised to `strength`, an SDEdit start):
  1. StableDiffusionControlNetPipeline text2img with the case's scheduler, steps, guidance_end
     and control window but without DeepCache or ToMe, the modes edge map as control, its
     initial latents drawn through pipeline_controlnet.randn_tensor replaced by `fixed`
     (= modes.noise), output_type="latent": the final latents L of its loop, i.e. the scaled
     latents (before the decode's 1 / vae.config.scaling_factor). Saved as <case>.start.
  2. StableDiffusionControlNetImg2ImgPipeline with image=L (a 4-channel tensor), the case's
     strength, the modes edge map as control_image, the img2img noise = modes.noise (its
     randn_tensor replaced as for the other img2img cases) and the case's speed-ups; only the
     last int(steps * strength) of the scheduler's steps run. <case>.image is its output.
  L goes in unchanged, with no VAE and no scaling (checked in diffusers 0.42.1's source):
  VaeImageProcessor.preprocess returns a torch tensor whose channel count equals its
  config.vae_latent_channels (4) as is ("don't need any preprocess if the image is latents"),
  and StableDiffusionControlNetImg2ImgPipeline.prepare_latents takes an image with
  image.shape[1] == 4 as init_latents directly; only its VAE-encode branch multiplies by
  vae.config.scaling_factor. So the start is scheduler.add_noise(L, modes.noise, t0) with t0
  the first timestep that runs, which the script also asserts on every such call (a wrapper
  of pipe.prepare_latents compares its input with L and its output with add_noise).

DeepCache: helper.set_params(...); helper.enable() before each pipeline call and
helper.disable() after. It wraps pipe.unet only, so the ControlNet runs at every step (stock).
Stock DeepCache cannot take the CFG cut-off: its cached block outputs keep both guidance rows
while the UNet then gets the conditional row only. So for the cases with both, the cut-off
callback (cfg_cutoff.DeepCacheCFGCutoffCallback, a subclass of its ControlNet one) also
replaces every tensor in helper.cached_output (inside tuples too) by its conditional half (the
last half of the batch rows) at the step the cut-off fires on, as the cut-off does for the
prompt embeddings and the control image.

ToMe: tomesd.apply_patch(pipe, ratio=...) with its defaults otherwise (max_downsample 1,
sx = sy = 2, use_rand, merging for self-attention only); tomesd.remove_patch(pipe) after. tomesd
draws its dst positions with torch.randint(sy * sx, size=(h // sy, w // sx, 1), generator=...)
from a fork of torch's global generator. So that Rust can draw the same, the script replaces
the module `torch` that tomesd/merge.py sees by a proxy (TorchWithStream) whose randint returns
values of this stream and which hands every other attribute to torch:

  SplitMix64, state = merge_seed (u64), new for each pipeline call:
    next(): state += 0x9E3779B97F4A7C15; z = state
            z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9
            z = (z ^ (z >> 27)) * 0x94D049BB133111EB
            return z ^ (z >> 31)                          (all mod 2^64)
    randint(n, (a, b, 1)) = next() % n for each element, row-major, int64

The stream runs on over all blocks and steps of the call in call order (tomesd draws only in
the transformer blocks at the top resolution, and only while the batch is even: not after the
CFG cut-off, nor in DeepCache's skipped blocks). merge_seed = 7 + the case's index.

Token order: tomesd splits the tokens into dst | src with an argsort of its -1/0 index buffer,
and torch's (default, unstable) CPU argsort does not keep the positions ascending within the
two groups (torch 2.15.0: most calls give another order). Only the order of the merged token
list depends on it, and attention and the merge's mean do not depend on that order but for
rounding. So the script checks, on every call of tomesd's bipartite_soft_matching_random2d
(from the index tensors its functions close over), that the dst and src token sets are the ones
the draw picks (dst of cell (i, j) with value v: row i*sy + v // sx, column j*sx + v % sx),
that no src token's best dst and no two of the similarity maxima it sorts are tied (so the
merges are unique), and it runs each ToMe case again with every Tensor.argsort in tomesd made
stable (the order the Rust side uses: dst positions ascending, then src positions ascending),
failing when the two images differ by STABLE_TOL or more. The fixtures are stock tomesd's.

After writing, it prints each case's max abs difference from the same settings without the
speed-ups and from the other cases of the same size, the init = "previous" cases' differences
from each other and from the same settings started from the modes frame (plain img2img), and
the UNet parts that ran at the full and the skipped steps of the DeepCache cases (forward hooks
on leaf convolutions).

The script runs torch on one thread (main): the committed fixtures are its one-thread output.

Needs the packages of make_modes_fixtures.py, and deepcache==0.1.1 tomesd==0.1.3.
Regenerate (after make_fixtures.py and make_modes_fixtures.py):
  python tools/diffuse/make_speedup_fixtures.py
"""

import json
import os

import torch
import tomesd
import tomesd.merge
from DeepCache import DeepCacheSDHelper
from diffusers import StableDiffusionControlNetImg2ImgPipeline, StableDiffusionControlNetPipeline
from diffusers.models.autoencoders import vae as vae_module
from diffusers.pipelines.controlnet import pipeline_controlnet, pipeline_controlnet_img2img
from PIL import Image
from safetensors.torch import load_file, save_file

from cfg_cutoff import cutoff_kwargs, speedup_cutoff_kwargs
from make_cutoff_fixtures import SCHEDULERS
from make_fixtures import SCHED_KW
from make_modes_fixtures import COND_SCALE, FIX, GUIDANCE, fixed, load_tiny

# name, mode, scheduler, steps, strength, guidance_end, control_start, control_end,
# cache_interval, cache_branch, token_merge_ratio, height, width
CASES = [
    ("dc_t2i_i2_b0_ddim", "text2img", "ddim", 6, 1.0, 1.0, 0.0, 1.0, 2, 0, 0.0, 64, 64),
    ("dc_t2i_i3_b1_unipc", "text2img", "unipc", 7, 1.0, 1.0, 0.0, 1.0, 3, 1, 0.0, 64, 64),
    ("dc_t2i_i2_b3_dpmpp2m", "text2img", "dpmpp2m", 6, 1.0, 1.0, 0.0, 1.0, 2, 3, 0.0, 64, 64),
    ("dc_t2i_i3_b5_ddim", "text2img", "ddim", 7, 1.0, 1.0, 0.0, 1.0, 3, 5, 0.0, 64, 64),
    ("dc_i2i_i2_b0_dpmpp2m", "img2img", "dpmpp2m", 8, 0.75, 1.0, 0.0, 1.0, 2, 0, 0.0, 64, 64),
    ("dc_cut_i3_b0_dpmpp2m", "text2img", "dpmpp2m", 8, 1.0, 0.4, 0.0, 0.75, 3, 0, 0.0, 64, 64),
    ("tome_r05_ddim", "text2img", "ddim", 6, 1.0, 1.0, 0.0, 1.0, 1, 0, 0.5, 64, 64),
    ("tome_r03_unipc", "text2img", "unipc", 6, 1.0, 1.0, 0.0, 1.0, 1, 0, 0.3, 64, 64),
    ("tome_cut_r05_dpmpp2m", "text2img", "dpmpp2m", 8, 1.0, 0.4, 0.0, 1.0, 1, 0, 0.5, 64, 64),
    ("tome_tall_r05_ddim", "text2img", "ddim", 5, 1.0, 1.0, 0.0, 1.0, 1, 0, 0.5, 128, 64),
    ("both_cut_dpmpp2m", "text2img", "dpmpp2m", 8, 1.0, 0.4, 0.0, 0.75, 3, 0, 0.5, 64, 64),
    ("both_i2i_unipc", "img2img", "unipc", 8, 0.75, 1.0, 0.0, 1.0, 2, 1, 0.5, 64, 64),
]
# init = "previous" (the docstring), appended after CASES (so merge_seed = 7 + 12, 13, 14); same
# fields as CASES, all img2img. prev_cpu: configs/zero-shot-cpu.toml's settings on the tiny models.
PREV_CASES = [
    ("prev_ddim", "img2img", "ddim", 6, 0.5, 1.0, 0.0, 1.0, 1, 0, 0.0, 64, 64),
    ("prev_unipc_s07", "img2img", "unipc", 8, 0.7, 1.0, 0.0, 1.0, 1, 0, 0.0, 64, 64),
    ("prev_cpu", "img2img", "dpmpp2m", 8, 0.5, 0.4, 0.0, 0.75, 3, 0, 0.5, 64, 64),
]
MERGE_SEED0 = 7
TALL_NOISE_SEED = 21
# Largest difference allowed between stock tomesd and tomesd with stable argsorts (rounding).
STABLE_TOL = 1e-5
MASK64 = (1 << 64) - 1


class SplitMix64:
    """The merge stream (see the docstring)."""

    def __init__(self, seed):
        self.state = seed & MASK64

    def next(self):
        self.state = (self.state + 0x9E3779B97F4A7C15) & MASK64
        z = self.state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK64
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK64
        return z ^ (z >> 31)


class TorchWithStream:
    """Stands in for `torch` in tomesd/merge.py: randint draws from a SplitMix64 stream (the
    generator tomesd passes is ignored), every other attribute is torch's. Keeps the draws."""

    def __init__(self, seed):
        self.stream = SplitMix64(seed)
        self.draws = []

    def randint(self, high, size, device=None, generator=None, **kw):
        assert not kw, kw
        n = 1
        for s in size:
            n *= s
        t = torch.tensor([self.stream.next() % high for _ in range(n)], dtype=torch.int64)
        t = t.reshape(tuple(size))
        self.draws.append(t)
        return t if device is None else t.to(device)

    def __getattr__(self, name):
        return getattr(torch, name)


ORIGINAL_BSM = tomesd.merge.bipartite_soft_matching_random2d
TORCH_ARGSORT = torch.Tensor.argsort
CHECKS = {"calls": 0, "draws": 0, "stable": 0, "unstable": 0, "force_stable": False, "latent_starts": 0}


def stable_argsort(self, dim=-1, descending=False, stable=False):
    return TORCH_ARGSORT(self, dim=dim, descending=descending, stable=True)


def checked_bsm(metric, w, h, sx, sy, r, no_rand=False, generator=None):
    """tomesd's bipartite_soft_matching_random2d, unchanged (or, with CHECKS["force_stable"],
    with every Tensor.argsort made stable), checking afterwards from the index tensors its
    functions close over: that its dst and src tokens are the ones the draw picks, whether
    torch's argsort of its index buffer gave the stable order, and that neither the best dst
    of a src token nor the greedy order of the src tokens has ties."""
    proxy = tomesd.merge.torch
    before = len(proxy.draws)
    if CHECKS["force_stable"]:
        torch.Tensor.argsort = stable_argsort
    try:
        merge, unmerge = ORIGINAL_BSM(metric, w, h, sx, sy, r, no_rand=no_rand, generator=generator)
    finally:
        torch.Tensor.argsort = TORCH_ARGSORT
    if r <= 0:
        return merge, unmerge
    CHECKS["calls"] += 1
    hsy, wsx = h // sy, w // sx
    if no_rand:
        assert len(proxy.draws) == before, "no_rand drew"
        rand = torch.zeros(hsy, wsx, dtype=torch.int64)
    else:
        assert len(proxy.draws) == before + 1, "one draw per call"
        rand = proxy.draws[-1][..., 0]
        CHECKS["draws"] += 1
    # dst of cell (i, j) with value v: row i*sy + v // sx, column j*sx + v % sx.
    is_dst = torch.zeros(h, w, dtype=torch.bool)
    for i in range(hsy):
        for j in range(wsx):
            v = int(rand[i, j])
            is_dst[i * sy + v // sx, j * sx + v % sx] = True
    flat = is_dst.flatten()
    pos = torch.arange(h * w)
    want_dst, want_src = pos[flat], pos[~flat]
    closed = dict(zip(unmerge.__code__.co_freevars, (c.cell_contents for c in unmerge.__closure__)))
    a_idx, b_idx = closed["a_idx"].flatten(), closed["b_idx"].flatten()
    assert torch.equal(b_idx.sort().values, want_dst), f"tomesd's dst tokens ({h}x{w})"
    assert torch.equal(a_idx.sort().values, want_src), f"tomesd's src tokens ({h}x{w})"
    if torch.equal(b_idx, want_dst) and torch.equal(a_idx, want_src):
        CHECKS["stable"] += 1
    else:
        CHECKS["unstable"] += 1
    # The similarities tomesd matches with (cosine, src x dst).
    m = metric / metric.norm(dim=-1, keepdim=True)
    scores = m[:, a_idx] @ m[:, b_idx].transpose(-1, -2)
    node_max = scores.max(dim=-1).values
    assert ((scores == node_max[..., None]).sum(-1) == 1).all(), "ties in a src token's best dst"
    for row in node_max:
        assert row.unique().numel() == row.numel(), "ties in tomesd's similarity maxima"
    return merge, unmerge


tomesd.merge.bipartite_soft_matching_random2d = checked_bsm
TEXT2IMG_RANDN = pipeline_controlnet.randn_tensor


class UnetTrace:
    """Forward hooks on leaf convolutions of the UNet's parts (DeepCache replaces the parts'
    forward, so hooks on the parts themselves would also fire on cached ones): per UNet call,
    the parts that really ran, and whether the timestep came positionally (args[1])."""

    def __init__(self, unet):
        self.calls, self.handles = [], []
        self.handles.append(unet.register_forward_pre_hook(self.start, with_kwargs=True))
        parts = [("conv_in", unet.conv_in)]
        for i, b in enumerate(unet.down_blocks):
            for j, a in enumerate(getattr(b, "attentions", None) or []):
                parts.append((f"down{i}.attn{j}", a.proj_in))
            for j, r in enumerate(b.resnets):
                parts.append((f"down{i}.resnet{j}", r.conv1))
            for d in b.downsamplers or []:
                parts.append((f"down{i}.downsample", d.conv))
        for j, a in enumerate(unet.mid_block.attentions):
            parts.append((f"mid.attn{j}", a.proj_in))
        for j, r in enumerate(unet.mid_block.resnets):
            parts.append((f"mid.resnet{j}", r.conv1))
        for i, b in enumerate(unet.up_blocks):
            for j, a in enumerate(getattr(b, "attentions", None) or []):
                parts.append((f"up{i}.attn{j}", a.proj_in))
            for j, r in enumerate(b.resnets):
                parts.append((f"up{i}.resnet{j}", r.conv1))
            for u in b.upsamplers or []:
                parts.append((f"up{i}.upsample", u.conv))
        parts.append(("conv_out", unet.conv_out))
        self.all = [n for n, _ in parts]
        for name, m in parts:
            self.handles.append(m.register_forward_hook(self.ran(name)))

    def start(self, module, args, kwargs):
        positional = len(args) >= 2 and torch.is_tensor(args[1])
        self.calls.append(dict(positional_t=positional, batch=args[0].shape[0], ran=[]))

    def ran(self, name):
        def hook(module, args, out):
            self.calls[-1]["ran"].append(name)

        return hook

    def remove(self):
        for h in self.handles:
            h.remove()


def make_start(parts, inputs, case):
    """The start latents L of an init = "previous" case (the docstring): stock text2img with the
    case's scheduler, steps and cut-offs, no speed-ups, initial latents = modes.noise through
    randn_tensor, output_type="latent". Returns L (1, 4, H/8, W/8)."""
    name, mode, sched, steps, strength, g_end, c_start, c_end, interval, branch, ratio, h, w = case
    pipe = StableDiffusionControlNetPipeline(scheduler=SCHEDULERS[sched].from_config(SCHED_KW), **parts)
    pipe.set_progress_bar_config(disable=True)
    control = Image.fromarray(inputs["edge"][(h, w)].to(torch.uint8).numpy()).convert("RGB")
    pipeline_controlnet.randn_tensor = fixed(inputs["noise"][(h, w)], "text2img noise")
    try:
        out = pipe(prompt_embeds=inputs["pos"], negative_prompt_embeds=inputs["neg"], image=control,
                   num_inference_steps=steps, guidance_scale=GUIDANCE,
                   controlnet_conditioning_scale=COND_SCALE, control_guidance_start=c_start,
                   control_guidance_end=c_end, height=h, width=w, output_type="latent",
                   **cutoff_kwargs(g_end, ["image"])).images
    finally:
        pipeline_controlnet.randn_tensor = TEXT2IMG_RANDN
    assert out.shape == (1, 4, h // 8, w // 8), out.shape
    return out.float().contiguous()


def check_latent_start(pipe, start, noise):
    """Wraps pipe.prepare_latents: asserts that the image it gets is `start` unchanged and that
    the latents it returns are scheduler.add_noise(start, noise, t0) (no VAE, no scaling)."""
    prepare = pipe.prepare_latents

    def checked(image, timestep, *args, **kwargs):
        assert torch.equal(image, start), "the latent start was changed before prepare_latents"
        latents = prepare(image, timestep, *args, **kwargs)
        want = pipe.scheduler.add_noise(start.clone(), noise.clone(), timestep)
        assert torch.equal(latents, want), "prepare_latents did not take the start as latents"
        CHECKS["latent_starts"] += 1
        return latents

    pipe.prepare_latents = checked


def run_case(parts, inputs, case, seed, cache=True, merge=True, trace=False, start=None):
    """One pipeline call; returns the image (1, 3, H, W), the merge draws and the UNet trace.
    With `start` (img2img only), the img2img call starts from those latents (init = "previous")
    instead of the modes frame."""
    name, mode, sched, steps, strength, g_end, c_start, c_end, interval, branch, ratio, h, w = case
    scheduler = SCHEDULERS[sched].from_config(SCHED_KW)
    call = dict(prompt_embeds=inputs["pos"], negative_prompt_embeds=inputs["neg"],
                num_inference_steps=steps, guidance_scale=GUIDANCE,
                controlnet_conditioning_scale=COND_SCALE, control_guidance_start=c_start,
                control_guidance_end=c_end, height=h, width=w, output_type="np")
    control = Image.fromarray(inputs["edge"][(h, w)].to(torch.uint8).numpy()).convert("RGB")
    if mode == "text2img":
        assert start is None, name
        pipe = StableDiffusionControlNetPipeline(scheduler=scheduler, **parts)
        args = dict(image=control, latents=inputs["noise"][(h, w)].clone())
        halves = ["image"]
    else:
        assert (h, w) == (64, 64)
        pipe = StableDiffusionControlNetImg2ImgPipeline(scheduler=scheduler, **parts)
        image = inputs["frame"] if start is None else start.clone()
        args = dict(image=image, control_image=control, strength=strength)
        halves = ["control_image"]
        if start is not None:
            check_latent_start(pipe, start, inputs["noise"][(h, w)])
    pipe.set_progress_bar_config(disable=True)

    helper = None
    if cache and interval > 1:
        helper = DeepCacheSDHelper(pipe=pipe)
        helper.set_params(cache_interval=interval, cache_branch_id=branch)
    if merge and ratio > 0:
        tomesd.apply_patch(pipe, ratio=ratio)
    proxy = TorchWithStream(seed)
    tomesd.merge.torch = proxy
    tracer = UnetTrace(pipe.unet) if trace else None
    if helper is not None:
        helper.enable()
    try:
        out = pipe(**call, **args, **speedup_cutoff_kwargs(g_end, halves, helper)).images
    finally:
        if helper is not None:
            helper.disable()
        if tracer is not None:
            tracer.remove()
        tomesd.merge.torch = torch
        tomesd.remove_patch(pipe)
    image = torch.from_numpy(out).permute(0, 3, 1, 2).float().contiguous()
    assert image.shape == (1, 3, h, w), image.shape
    return image, proxy.draws, tracer


def describe(tracer):
    """The distinct sets of UNet parts that ran, with the call indices that ran them."""
    groups = {}
    for k, c in enumerate(tracer.calls):
        groups.setdefault(tuple(c["ran"]), []).append(k)
    lines = []
    for ran, ks in groups.items():
        kind = "full" if set(ran) == set(tracer.all) else "skip"
        skipped = [n for n in tracer.all if n not in ran]
        lines.append(f"    {kind} calls {ks}: ran {' '.join(ran)}"
                     + (f"\n      not run: {' '.join(skipped)}" if skipped else ""))
    return "\n".join(lines)


def main():
    # One thread: the CPU kernels' sums are then in one order, so the fixtures come out byte for
    # byte the same on a machine whatever its core count or load (with 2 threads they differ by
    # rounding, ~4e-6).
    torch.set_num_threads(1)
    unet, controlnet, vae, text, pos, neg = load_tiny()
    m = load_file(os.path.join(FIX, "modes.safetensors"))
    edge64 = m["modes.edge"]
    noise, enc_eps = m["modes.noise"], m["modes.enc_eps"]
    tall_noise = torch.randn((1, 4, 16, 8), generator=torch.Generator().manual_seed(TALL_NOISE_SEED))
    inputs = dict(
        pos=pos, neg=neg,
        frame=Image.fromarray(m["modes.frame"].to(torch.uint8).numpy()),
        edge={(64, 64): edge64, (128, 64): torch.cat([edge64, edge64], 0)},
        noise={(64, 64): noise, (128, 64): tall_noise},
    )
    vae_module.randn_tensor = fixed(enc_eps, "VAE latent sample")
    pipeline_controlnet_img2img.randn_tensor = fixed(noise, "img2img noise")

    parts = dict(vae=vae, text_encoder=text, tokenizer=None, unet=unet, controlnet=controlnet,
                 safety_checker=None, feature_extractor=None, requires_safety_checker=False)
    exp, listed, report, from_frame = {}, [], [], {}
    all_cases = [(c, "noise") for c in CASES] + [(c, "previous") for c in PREV_CASES]
    with torch.no_grad():
        for idx, (case, init) in enumerate(all_cases):
            name, mode, sched, steps, strength, g_end, c_start, c_end, interval, branch, ratio, h, w = case
            seed = MERGE_SEED0 + idx
            start = None
            if init == "previous":
                start = make_start(parts, inputs, case)
                assert torch.isfinite(start).all(), name
                assert torch.equal(start, make_start(parts, inputs, case)), f"{name}: start not reproducible"
                exp[f"{name}.start"] = start
            image, draws, tracer = run_case(parts, inputs, case, seed, trace=interval > 1, start=start)
            assert torch.isfinite(image).all(), name
            exp[f"{name}.image"] = image
            if (h, w) != (64, 64):
                exp[f"{name}.noise"] = inputs["noise"][(h, w)].float().contiguous()
                exp[f"{name}.edge"] = inputs["edge"][(h, w)].float().contiguous()
            listed.append(dict(name=name, mode=mode, scheduler=sched, steps=steps, strength=strength,
                               guidance_scale=GUIDANCE, conditioning_scale=COND_SCALE,
                               guidance_end=g_end, control_start=c_start, control_end=c_end,
                               cache_interval=interval, cache_branch=branch,
                               token_merge_ratio=ratio, merge_seed=seed, height=h, width=w, init=init))
            sped = interval > 1 or ratio > 0
            base = image
            if sped:
                base, _, _ = run_case(parts, inputs, case, seed, cache=False, merge=False, start=start)
            again, draws2, _ = run_case(parts, inputs, case, seed, start=start)
            assert torch.equal(image, again), f"{name}: not reproducible"
            assert [d.tolist() for d in draws] == [d.tolist() for d in draws2]
            stable_diff = None
            if ratio > 0:
                CHECKS["force_stable"] = True
                stable, _, _ = run_case(parts, inputs, case, seed, start=start)
                CHECKS["force_stable"] = False
                stable_diff = (image - stable).abs().max().item()
                assert stable_diff < STABLE_TOL, f"{name}: the argsort order matters ({stable_diff})"
            if start is not None:
                # The same call started from the modes frame (plain img2img), to show the start matters.
                from_frame[name], _, _ = run_case(parts, inputs, case, seed)
            report.append((name, (image - base).abs().max().item() if sped else None, draws, tracer,
                           stable_diff))
    save_file(exp, os.path.join(FIX, "speedups.safetensors"))
    with open(os.path.join(FIX, "speedups.json"), "w") as f:
        json.dump(listed, f, indent=1)
    print("wrote", os.path.join(FIX, "speedups.safetensors"), "and speedups.json")

    print("max abs difference from the same settings without the speed-ups:")
    for name, diff, draws, tracer, stable_diff in report:
        shapes = sorted({tuple(d.shape) for d in draws})
        extra = "" if stable_diff is None else f"  from stable argsorts {stable_diff:.2e}"
        if diff is None:
            print(f"  {name:24} -        (no speed-ups)")
            continue
        print(f"  {name:24} {diff:.5f}  merge draws {len(draws)} {shapes}{extra}")
        assert diff > 1e-4, f"{name}: the speed-up changed nothing"
    print(f'init = "previous" ({CHECKS["latent_starts"]} img2img calls took the start as latents, '
          f"unscaled): max abs difference")
    prev = [c[0] for c in PREV_CASES]
    for name in prev:
        d = (exp[f"{name}.image"] - from_frame[name]).abs().max().item()
        print(f"  {name:24} from the same call started from the modes frame (plain img2img) {d:.5f}")
        assert d > 1e-4, f"{name}: the start changed nothing"
    for i, a in enumerate(prev):
        for b in prev[i + 1:]:
            d = (exp[f"{a}.image"] - exp[f"{b}.image"]).abs().max().item()
            print(f"  {a} vs {b}: {d:.5f}")
    names = [c[0] for c in CASES + PREV_CASES]
    least = None
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            x, y = exp[f"{a}.image"], exp[f"{b}.image"]
            if x.shape == y.shape:
                d = (x - y).abs().max().item()
                assert d > 1e-4, f"{a} == {b}"
                least = min(least or (d, a, b), (d, a, b))
    print(f"closest two cases: {least[1]} and {least[2]}, max abs difference {least[0]:.5f}")
    print(f"tomesd: {CHECKS['calls']} merges, {CHECKS['draws']} with a draw; torch's argsort of the "
          f"index buffer gave the stable order in {CHECKS['stable']}, another in {CHECKS['unstable']}")
    print("DeepCache: UNet parts run per call (hooks on leaf convolutions)")
    for (name, _, _, tracer, _), case in zip(report, CASES + PREV_CASES):
        if tracer is None:
            continue
        pos_t = all(c["positional_t"] for c in tracer.calls)
        print(f"  {name} (interval {case[8]}, branch {case[9]}), timestep positional: {pos_t}, "
              f"batches {[c['batch'] for c in tracer.calls]}")
        print(describe(tracer))


if __name__ == "__main__":
    main()
