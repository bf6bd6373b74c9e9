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
  report   JSONL            the markdown table for BENCHMARKS.md from the JSON lines of a run.

Needs: torch (2.11+cu130 on the GPU machines), diffusers==0.42.1 (carried as wheels, see
tools/gpu/README.md), transformers, safetensors, opencv-python-headless, numpy, pillow.
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
                           StableDiffusionControlNetPipeline, UNet2DConditionModel, UniPCMultistepScheduler)

    sys.path.insert(0, os.path.join(ROOT, "tools", "diffuse"))
    from cfg_cutoff import cutoff_kwargs

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
    load_s = time.perf_counter() - t0
    names = sorted(f for f in os.listdir(args.edges) if f.endswith(".png"))
    edges = [Image.open(os.path.join(args.edges, f)).convert("RGB") for f in names]
    size = edges[0].width
    sync = torch.cuda.synchronize if dev.startswith("cuda") else (lambda: None)
    per_frame, k = [], 0
    for call in range(args.warmup + -(-args.frames // args.batch)):
        images = [edges[(k + j) % len(edges)] for j in range(args.batch)]
        k += args.batch
        gen = [torch.Generator(dev).manual_seed(k + j) for j in range(args.batch)]
        sync()
        t = time.perf_counter()
        out = pipe([PROMPT] * args.batch, image=images, negative_prompt=[NEGATIVE] * args.batch,
                   num_inference_steps=args.steps, guidance_scale=7.5, height=size, width=size,
                   control_guidance_start=args.control_start, control_guidance_end=args.control_end,
                   generator=gen, output_type="np", **cutoff_kwargs(args.guidance_end, ["image"])).images
        sync()
        s = time.perf_counter() - t
        assert len(out) == args.batch and np.asarray(out).shape[1:3] == (size, size)
        if call >= args.warmup:
            per_frame += [s / args.batch] * args.batch
    per_frame = per_frame[:args.frames]
    print(json.dumps({
        "impl": "diffusers", "device": dev, "dtype": args.dtype, "steps": args.steps, "batch": args.batch,
        "scheduler": args.scheduler, "guidance_end": args.guidance_end,
        "control_guidance": [args.control_start, args.control_end],
        "size": size, "load_s": round(load_s, 3), "median_s": round(statistics.median(per_frame), 4),
        "per_frame_s": [round(s, 4) for s in per_frame],
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
    a = sub.add_parser("report")
    a.add_argument("jsonl")
    args = p.parse_args()
    {"prepare": prepare, "diffusers": diffusers_run, "report": report}[args.cmd](args)


if __name__ == "__main__":
    main()
