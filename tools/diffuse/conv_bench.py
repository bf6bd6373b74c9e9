#!/usr/bin/env python3
"""torch's side of gait-diffuse's examples/conv_bench.rs: the same 3x3 convolutions and
linear layers at SD 1.5's shapes, f32, 2 threads, GFLOP/s (best of 5), and diffusers'
attention layer (its default processor, torch's scaled_dot_product_attention)."""
import time

import torch
from diffusers.models.attention_processor import Attention

torch.set_num_threads(2)


def best(f):
    f()
    out = []
    for _ in range(5):
        t = time.perf_counter()
        f()
        out.append(time.perf_counter() - t)
    return min(out)


with torch.no_grad():
    for c, hw in [(320, 64), (640, 32), (1280, 16), (1280, 8)]:
        conv = torch.nn.Conv2d(c, c, 3, padding=1)
        x = torch.randn(2, c, hw, hw)
        s = best(lambda: conv(x))
        flop = 2 * 2 * hw * hw * 9 * c * c
        print(f"conv3x3 c={c} {hw}x{hw} b2: {flop / s / 1e9:.1f} GFLOP/s ({s * 1e3:.1f} ms)")
    for m, k, n in [(8192, 320, 2560), (4096, 2880, 320), (2048, 640, 640)]:
        lin = torch.nn.Linear(k, n, bias=False)
        x = torch.randn(m, k)
        s = best(lambda: lin(x))
        print(f"linear {m}x{k}x{n} (torch): {2 * m * k * n / s / 1e9:.1f} GFLOP/s ({s * 1e3:.1f} ms)")
    for n, c, m, ctx_c in [(4096, 320, 4096, 320), (1024, 640, 1024, 640), (4096, 320, 77, 768)]:
        attn = Attention(c, cross_attention_dim=ctx_c, heads=8, dim_head=c // 8).eval()
        x = torch.randn(2, n, c)
        ctx = torch.randn(2, m, ctx_c) if m != n else None
        s = best(lambda: attn(x, encoder_hidden_states=ctx))
        print(f"attention b2 {n}x{c} over {m}x{ctx_c}, 8 heads: {s * 1e3:.1f} ms")
