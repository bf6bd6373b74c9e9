#!/usr/bin/env python3
"""GPU benchmark helpers for tools/gpu/bench_regen.sh (which runs them; see tools/gpu/README.md).

  prepare  OUT [--tiny]     random SD 1.5 UNet + VAE + CLIP text encoder + canny ControlNet in
                            diffusers layout (seeded; the real configs, or the test fixtures'
                            tiny ones with --tiny), the CLIP tokenizer (vocab.json rebuilt from
                            the committed merges.txt as CLIP builds it), canny edge maps of the
                            sample video's frames (OUT/edges, square), and OUT/frames: N frames
                            of the sample video, forward then backward, as JPEGs for `gait run`.
  diffusers WEIGHTS EDGES   StableDiffusionControlNetPipeline on those weights and edge maps:
                            UniPC (or --scheduler), guidance 7.5, the paper's prompts, optional
                            cut-offs (--guidance-end, --control-start/--control-end), one JSON line
                            of per-frame seconds (the first --warmup calls untimed), like regen_bench's.
                            Issue 30's speed-ups (tools/diffuse/bench_regen_cpu.sh, cpu setting):
                            --cache-interval N --cache-branch B: DeepCache 0.1.1's DeepCacheSDHelper
                              (set_params(cache_interval, cache_branch_id)), enabled before each
                              pipeline call and disabled after; with --guidance-end < 1 the cut-off
                              also halves its cached outputs (cfg_cutoff.DeepCacheCFGCutoffCallback,
                              as make_speedup_fixtures.py).
                            --token-merge-ratio R: tomesd 0.1.3's apply_patch(pipe, ratio=R), its
                              other defaults (stock tomesd, its own random draws).
                            --height H: each square edge map resized to H x H first (Pillow's
                              bilinear, as regen_bench's `height`);
                            --width W: each square edge map cropped to its middle W columns, so the
                              calls run at height = the maps' size, width = W.
                            --init previous --strength S: the timed frames run one at a time on
                              consecutive edge maps; the first is text2img from noise (as without
                              it), each later one StableDiffusionControlNetImg2ImgPipeline (the same
                              components) with image = the previous frame's final latents (scaled,
                              taken as latents as is) noised to strength S, so int(steps * S)
                              steps run. Every frame returns its latents (output_type="latent")
                              and is then decoded by the VAE inside its timing. The JSON line's
                              first_s is the first timed frame, median_s the median of the later
                              ones (needs --frames >= 2 and --batch 1); --warmup calls are untimed
                              text2img frames before the chain.
  report   JSONL            the markdown table for BENCHMARKS.md from the JSON lines of a run.

Needs: torch (2.11+cu130 on the GPU machines), diffusers==0.42.1 (carried as wheels, see
tools/gpu/README.md), transformers, safetensors, opencv-python-headless, numpy, pillow; with
the speed-up options deepcache==0.1.1 and tomesd==0.1.3.
"""

import argparse
import json
import os
import statistics
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
FIXTURES = os.path.join(ROOT, "crates", "gait-diffuse", "tests", "fixtures", "tiny")
MERGES = os.path.join(FIXTURES, "tokenizer", "merges.txt")
VIDEO = os.path.join(ROOT, "data", "sample", "sports2d-demo.mp4")
PROMPT = "an able-body person walking, intact lower limbs, 2 legs, full-body portrait, realistic"
NEGATIVE = "cyborg, amputee, panfuturism"
# runwayml/stable-diffusion-v1-5 scheduler/scheduler_config.json, the keys UniPC takes (the
# schedule our UniPC uses).
SCHEDULER = dict(
    num_train_timesteps=1000, beta_start=0.00085, beta_end=0.012, beta_schedule="scaled_linear",
    steps_offset=1, prediction_type="epsilon",
)


def real_configs():
    sys.path.insert(0, os.path.join(ROOT, "tools", "diffuse"))
    import make_manifest as m  # the SD 1.5 / sd-controlnet-canny configs, in one place

    return m.UNET, m.CONTROLNET, m.VAE, m.TEXT


def tiny_configs():
    def cfg(name):
        with open(os.path.join(FIXTURES, name, "config.json")) as f:
            return {k: v for k, v in json.load(f).items() if not k.startswith("_")}

    text = cfg("text_encoder")
    for k in ("architectures", "dtype", "torch_dtype", "transformers_version"):
        text.pop(k, None)
    return cfg("unet"), cfg("controlnet"), cfg("vae"), text


def clip_vocab(merges_path):
    """CLIP's vocabulary from its merges: the 256 byte symbols, the same with </w>, one token
    per merge, then the two special tokens (openai/CLIP simple_tokenizer.py)."""
    bs = list(range(ord("!"), ord("~") + 1)) + list(range(ord("¡"), ord("¬") + 1)) + list(range(ord("®"), ord("ÿ") + 1))
    cs, n = bs[:], 0
    for b in range(256):
        if b not in bs:
            bs.append(b)
            cs.append(256 + n)
            n += 1
    symbols = [chr(c) for c in cs]
    with open(merges_path, encoding="utf-8") as f:
        merges = [tuple(line.split()) for line in f.read().split("\n")[1:] if line.strip()]
    vocab = symbols + [s + "</w>" for s in symbols] + ["".join(m) for m in merges]
    vocab += ["<|startoftext|>", "<|endoftext|>"]
    return {t: i for i, t in enumerate(vocab)}


def write_frames(out, frames, size):
    """Edge maps (square crop of the middle, `size` px, canny 100/200 as the ControlNet
    annotator) and `frames` video frames (forward, then backward) for the e2e run."""
    import cv2

    cap = cv2.VideoCapture(VIDEO)
    video = []
    while True:
        ok, img = cap.read()
        if not ok:
            break
        video.append(img)
    if not video:
        raise SystemExit(f"cannot read {VIDEO}")
    os.makedirs(os.path.join(out, "edges"), exist_ok=True)
    os.makedirs(os.path.join(out, "frames"), exist_ok=True)
    for i, img in enumerate(video[::10][:16]):
        h, w = img.shape[:2]
        s = min(h, w)
        crop = img[(h - s) // 2:(h + s) // 2, (w - s) // 2:(w + s) // 2]
        gray = cv2.cvtColor(cv2.resize(crop, (size, size), interpolation=cv2.INTER_AREA), cv2.COLOR_BGR2GRAY)
        cv2.imwrite(os.path.join(out, "edges", f"{i:03d}.png"), cv2.Canny(gray, 100, 200))
    order = list(range(len(video))) + list(range(len(video) - 2, 0, -1))
    while len(order) < frames:
        order += order
    for k, i in enumerate(order[:frames]):
        cv2.imwrite(os.path.join(out, "frames", f"{k:06d}.jpg"), video[i], [cv2.IMWRITE_JPEG_QUALITY, 95])


def prepare(args):
    import torch
    from diffusers import AutoencoderKL, ControlNetModel, UNet2DConditionModel
    from transformers import CLIPTextConfig, CLIPTextModel

    unet_cfg, cn_cfg, vae_cfg, text_cfg = tiny_configs() if args.tiny else real_configs()
    sd = os.path.join(args.out, "sd")
    torch.manual_seed(0)
    with torch.no_grad():
        unet = UNet2DConditionModel.from_config(unet_cfg)
        unet.save_pretrained(os.path.join(sd, "unet"))
        del unet
        cn = ControlNetModel.from_config(cn_cfg)
        for p in cn.parameters():  # zero convs would make the ControlNet trivial
            p.normal_(0, 0.02)
        cn.save_pretrained(os.path.join(args.out, "controlnet"))
        del cn
        AutoencoderKL.from_config(vae_cfg).save_pretrained(os.path.join(sd, "vae"))
        CLIPTextModel(CLIPTextConfig(**text_cfg)).save_pretrained(os.path.join(sd, "text_encoder"))
    tok = os.path.join(sd, "tokenizer")
    os.makedirs(tok, exist_ok=True)
    with open(MERGES, encoding="utf-8") as src, open(os.path.join(tok, "merges.txt"), "w", encoding="utf-8") as dst:
        dst.write(src.read())
    with open(os.path.join(tok, "vocab.json"), "w", encoding="utf-8") as f:
        json.dump(clip_vocab(MERGES), f, ensure_ascii=False)
    write_frames(args.out, args.frames, args.size)
    print(f"prepared {args.out} ({'tiny' if args.tiny else 'SD 1.5 size'} random weights, seed 0)")


def diffusers_run(args):
    import numpy as np
    import torch
    from diffusers import (AutoencoderKL, ControlNetModel, DDIMScheduler, DPMSolverMultistepScheduler,
                           StableDiffusionControlNetImg2ImgPipeline, StableDiffusionControlNetPipeline,
                           UNet2DConditionModel, UniPCMultistepScheduler)

    sys.path.insert(0, os.path.join(ROOT, "tools", "diffuse"))
    from cfg_cutoff import speedup_cutoff_kwargs

    previous = args.init == "previous"
    if previous and (args.batch != 1 or args.frames < 2):
        raise SystemExit("--init previous needs --batch 1 and --frames >= 2 (the first frame and the rest)")
    if not 0.0 < args.strength <= 1.0:
        raise SystemExit(f"--strength {args.strength}: must be in (0, 1]")
    scheduler = {"unipc": UniPCMultistepScheduler, "ddim": DDIMScheduler,
                 "dpmpp2m": DPMSolverMultistepScheduler}[args.scheduler]
    from PIL import Image
    from transformers import CLIPTextModel, CLIPTokenizer

    dev = args.device
    dtype = {"f32": torch.float32, "f16": torch.float16, "bf16": torch.bfloat16}[args.dtype]
    sd = os.path.join(args.weights, "sd")
    t0 = time.perf_counter()
    pipe = StableDiffusionControlNetPipeline(
        vae=AutoencoderKL.from_pretrained(os.path.join(sd, "vae"), torch_dtype=dtype),
        text_encoder=CLIPTextModel.from_pretrained(os.path.join(sd, "text_encoder"), torch_dtype=dtype),
        tokenizer=CLIPTokenizer(os.path.join(sd, "tokenizer", "vocab.json"), os.path.join(sd, "tokenizer", "merges.txt"),
                                model_max_length=77),
        unet=UNet2DConditionModel.from_pretrained(os.path.join(sd, "unet"), torch_dtype=dtype),
        controlnet=ControlNetModel.from_pretrained(os.path.join(args.weights, "controlnet"), torch_dtype=dtype),
        scheduler=scheduler(**SCHEDULER),
        safety_checker=None, feature_extractor=None, requires_safety_checker=False,
    ).to(dev)
    pipe.set_progress_bar_config(disable=True)
    # The same modules (and scheduler) for the frames that start from the previous latents.
    img2img = (StableDiffusionControlNetImg2ImgPipeline(**pipe.components, requires_safety_checker=False)
               if previous else None)
    if img2img is not None:
        img2img.set_progress_bar_config(disable=True)
    helpers = {}
    if args.cache_interval > 1:
        from DeepCache import DeepCacheSDHelper

        for p in filter(None, [pipe, img2img]):
            helpers[id(p)] = DeepCacheSDHelper(pipe=p)
            helpers[id(p)].set_params(cache_interval=args.cache_interval, cache_branch_id=args.cache_branch)
    if args.token_merge_ratio > 0:
        import tomesd

        tomesd.apply_patch(pipe, ratio=args.token_merge_ratio)  # patches pipe.unet, shared by img2img
    load_s = time.perf_counter() - t0

    names = sorted(f for f in os.listdir(args.edges) if f.endswith(".png"))
    edges = [Image.open(os.path.join(args.edges, f)).convert("RGB") for f in names]
    if args.height:
        edges = [e.resize((args.height, args.height), Image.BILINEAR) for e in edges]
    height = edges[0].height
    width = args.width or edges[0].width
    if width > edges[0].width or width % 8:
        raise SystemExit(f"--width {width}: must be a multiple of 8 and at most the maps' {edges[0].width}")
    if width != edges[0].width:
        left = (edges[0].width - width) // 2
        edges = [e.crop((left, 0, left + width, e.height)) for e in edges]
    sync = torch.cuda.synchronize if dev.startswith("cuda") else (lambda: None)
    common = dict(num_inference_steps=args.steps, guidance_scale=7.5, height=height, width=width,
                  control_guidance_start=args.control_start, control_guidance_end=args.control_end)

    def call(p, batch_prompts, gen, **kw):
        """One pipeline call with DeepCache enabled around it (when on) and the cut-off."""
        helper = helpers.get(id(p))
        halves = ["control_image"] if p is img2img else ["image"]
        if helper is not None:
            helper.enable()
        try:
            return p(batch_prompts, negative_prompt=[NEGATIVE] * len(batch_prompts), generator=gen,
                     **common, **kw, **speedup_cutoff_kwargs(args.guidance_end, halves, helper)).images
        finally:
            if helper is not None:
                helper.disable()

    @torch.no_grad()
    def decode(latents):
        image = pipe.vae.decode(latents / pipe.vae.config.scaling_factor, return_dict=False)[0]
        return pipe.image_processor.postprocess(image, output_type="np")

    per_frame, k = [], 0
    if not previous:
        for c in range(args.warmup + -(-args.frames // args.batch)):
            images = [edges[(k + j) % len(edges)] for j in range(args.batch)]
            k += args.batch
            gen = [torch.Generator(dev).manual_seed(k + j) for j in range(args.batch)]
            sync()
            t = time.perf_counter()
            out = call(pipe, [PROMPT] * args.batch, gen, image=images, output_type="np")
            sync()
            s = time.perf_counter() - t
            assert len(out) == args.batch and np.asarray(out).shape[1:3] == (height, width)
            if c >= args.warmup:
                per_frame += [s / args.batch] * args.batch
        per_frame = per_frame[:args.frames]
        first_s, median_s = per_frame[0], statistics.median(per_frame)
    else:
        latents = None
        for c in range(args.warmup + args.frames):
            # Untimed warm-up frames, then the chain: frame 0 from noise, the others from the latents
            # of the frame before.
            image = edges[k % len(edges)]
            k += 1
            gen = torch.Generator(dev).manual_seed(k)
            chain = c >= args.warmup
            sync()
            t = time.perf_counter()
            if not chain or c == args.warmup:
                latents = call(pipe, [PROMPT], gen, image=image, output_type="latent")
            else:
                latents = call(img2img, [PROMPT], gen, image=latents, control_image=image,
                               strength=args.strength, output_type="latent")
            out = decode(latents)
            sync()
            s = time.perf_counter() - t
            assert latents.shape[1] == 4 and np.asarray(out).shape[1:3] == (height, width)
            if chain:
                per_frame.append(s)
        first_s, median_s = per_frame[0], statistics.median(per_frame[1:])
    print(json.dumps({
        "impl": "diffusers", "device": dev, "dtype": args.dtype, "steps": args.steps, "batch": args.batch,
        "scheduler": args.scheduler, "guidance_end": args.guidance_end,
        "control_guidance": [args.control_start, args.control_end],
        "cache_interval": args.cache_interval, "cache_branch": args.cache_branch,
        "token_merge_ratio": args.token_merge_ratio, "init": args.init, "strength": args.strength,
        "size": height, "width": width, "load_s": round(load_s, 3), "first_s": round(first_s, 4),
        "median_s": round(median_s, 4), "per_frame_s": [round(s, 4) for s in per_frame],
        "torch": torch.__version__, "diffusers": __import__("diffusers").__version__,
    }), flush=True)


def report(args):
    rows = [json.loads(line) for line in open(args.jsonl) if line.startswith("{")]
    runs = [r for r in rows if "impl" in r]
    meta = next((r for r in rows if "gpu" in r), {})
    if not runs:
        raise SystemExit(f"{args.jsonl}: no benchmark results")
    print(f"### ControlNet regeneration on the GPU ({meta.get('date', '?')}, {meta.get('gpu', '?')})\n")
    weights = "Tiny random weights (the tests' configs; times mean nothing)" if meta.get("tiny") else "Random SD 1.5-size weights"
    print(f"{weights} (seed 0), {runs[0]['size']}x{runs[0]['size']}, {runs[0]['steps']} UniPC steps, "
          f"guidance 7.5 (batch 2 through UNet + ControlNet), the paper's prompts; per-frame seconds, "
          f"median over every timed frame of {meta.get('rounds', '?')} interleaved rounds "
          f"(torch {next((r['torch'] for r in runs if 'torch' in r), '?')}, "
          f"diffusers {next((r['diffusers'] for r in runs if 'diffusers' in r), '?')}).\n")
    print("| implementation | dtype | batch | s/frame | it/s | frames/s | vs diffusers |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    groups = {}
    for r in runs:
        groups.setdefault((r["impl"], r["dtype"], r["batch"]), []).extend(r["per_frame_s"])
    base = {k[1]: statistics.median(v) for k, v in groups.items() if k[0] == "diffusers"}
    for (impl, dtype, batch), times in sorted(groups.items()):
        med = statistics.median(times)
        ratio = f"{base[dtype] / med:.2f}x" if dtype in base else "-"
        print(f"| {impl} | {dtype} | {batch} | {med:.3f} | {runs[0]['steps'] / med:.1f} | {1 / med:.2f} | {ratio} |")
    for r in rows:
        if "e2e_s" in r:
            print(f"\nEnd to end: `gait run` on {r['frames']} frames ({r['width']}x{r['height']}), "
                  f"[selection] mode = \"poor\", regenerator on {r['device']} ({r['dtype']}, batch {r['batch']}): "
                  f"{r['e2e_s']:.1f} s wall clock, {r['regenerated']} frames regenerated "
                  f"(target: < 60 s on one H100).")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("prepare")
    a.add_argument("out")
    a.add_argument("--tiny", action="store_true", help="the test fixtures' tiny configs (CPU dry run)")
    a.add_argument("--frames", type=int, default=300)
    a.add_argument("--size", type=int, default=512)
    a = sub.add_parser("diffusers")
    a.add_argument("weights")
    a.add_argument("edges")
    a.add_argument("--device", default="cuda")
    a.add_argument("--dtype", default="f16", choices=["f32", "f16", "bf16"])
    a.add_argument("--steps", type=int, default=20)
    a.add_argument("--scheduler", default="unipc", choices=["unipc", "ddim", "dpmpp2m"])
    a.add_argument("--guidance-end", type=float, default=1.0, help="CFG cut-off (cfg_cutoff.py)")
    a.add_argument("--control-start", type=float, default=0.0)
    a.add_argument("--control-end", type=float, default=1.0)
    a.add_argument("--batch", type=int, default=1)
    a.add_argument("--frames", type=int, default=8)
    a.add_argument("--warmup", type=int, default=1)
    a.add_argument("--cache-interval", type=int, default=1, help="DeepCache's cache_interval (1: off)")
    a.add_argument("--cache-branch", type=int, default=0, help="DeepCache's cache_branch_id")
    a.add_argument("--token-merge-ratio", type=float, default=0.0, help="tomesd's ratio (0: off)")
    a.add_argument("--height", type=int, default=0, help="resize the square edge maps to H x H first")
    a.add_argument("--width", type=int, default=0, help="crop the edge maps to their middle W columns")
    a.add_argument("--init", default="noise", choices=["noise", "previous"])
    a.add_argument("--strength", type=float, default=1.0, help="with --init previous")
    a = sub.add_parser("report")
    a.add_argument("jsonl")
    args = p.parse_args()
    {"prepare": prepare, "diffusers": diffusers_run, "report": report}[args.cmd](args)


if __name__ == "__main__":
    main()
