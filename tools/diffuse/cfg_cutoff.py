"""diffusers' classifier-free-guidance cut-off for its ControlNet pipelines (SD 1.5).

SDCFGCutoffCallback turns guidance off after step int(num_timesteps * cutoff_step_ratio) and
keeps the conditional row of the prompt embeddings. A ControlNet pipeline also holds its control
image twice (one per guidance row), so this callback keeps its conditional row too, as diffusers'
SDXLControlnetCFGCutoffCallback does for SDXL; and the inpainting pipeline's mask and
masked-image latents. Used by make_cutoff_fixtures.py and tools/gpu/bench_diffusers.py.

With DeepCache (DeepCacheSDHelper of deepcache 0.1.1), whose cached block outputs keep both
guidance rows, DeepCacheCFGCutoffCallback also keeps the conditional half of that cache when the
cut-off fires (make_speedup_fixtures.py; speedup_cutoff_kwargs picks the callback).
"""

import torch
from diffusers.callbacks import SDCFGCutoffCallback


class ControlNetCFGCutoffCallback(SDCFGCutoffCallback):
    """SDCFGCutoffCallback that also keeps the conditional half of the other per-guidance-row
    inputs: the control image, and the inpainting pipeline's mask and masked-image latents."""

    def __init__(self, cutoff_step_ratio, halves):
        super().__init__(cutoff_step_ratio=cutoff_step_ratio)
        self.halves = halves
        self.tensor_inputs = ["prompt_embeds", *halves]

    def callback_fn(self, pipeline, step_index, timestep, callback_kwargs):
        cutoff = int(pipeline.num_timesteps * self.config.cutoff_step_ratio)
        if step_index == cutoff:
            callback_kwargs = super().callback_fn(pipeline, step_index, timestep, callback_kwargs)
            for key in self.halves:
                t = callback_kwargs[key]
                if t is None:
                    continue
                if key in ("mask", "masked_image_latents"):
                    # The inpainting pipeline does not take these back from the callback's
                    # output (diffusers 0.42.1), so shrink its own tensor in place.
                    t.data = t.data[-1:].clone()
                else:
                    callback_kwargs[key] = t[-1:]
        return callback_kwargs


def cutoff_kwargs(guidance_end, halves):
    """The pipeline call's callback arguments for `guidance_end` (none at 1.0)."""
    if guidance_end >= 1.0:
        return {}
    cb = ControlNetCFGCutoffCallback(guidance_end, halves)
    return dict(callback_on_step_end=cb, callback_on_step_end_tensor_inputs=cb.tensor_inputs)


def conditional_half(x):
    """The last half of the batch rows of every tensor in `x` (tensors in nested tuples)."""
    if torch.is_tensor(x):
        assert x.shape[0] % 2 == 0, x.shape
        return x[x.shape[0] // 2:]
    if isinstance(x, (tuple, list)):
        return type(x)(conditional_half(y) for y in x)
    raise TypeError(f"DeepCache cached a {type(x)}")


class DeepCacheCFGCutoffCallback(ControlNetCFGCutoffCallback):
    """ControlNetCFGCutoffCallback that, when the cut-off fires, also keeps the conditional half of
    DeepCache's cached block outputs (stock DeepCache would feed the one-row UNet its two-row
    cache at the next skipped step)."""

    def __init__(self, cutoff_step_ratio, halves, helper):
        super().__init__(cutoff_step_ratio, halves)
        self.helper = helper

    def callback_fn(self, pipeline, step_index, timestep, callback_kwargs):
        callback_kwargs = super().callback_fn(pipeline, step_index, timestep, callback_kwargs)
        if step_index == int(pipeline.num_timesteps * self.config.cutoff_step_ratio):
            cache = self.helper.cached_output
            for key in cache:
                cache[key] = conditional_half(cache[key])
        return callback_kwargs


def speedup_cutoff_kwargs(guidance_end, halves, helper):
    """cutoff_kwargs, with DeepCacheCFGCutoffCallback when DeepCache is on (`helper`, the
    DeepCacheSDHelper enabled around the call; None without DeepCache)."""
    if guidance_end >= 1.0 or helper is None:
        return cutoff_kwargs(guidance_end, halves)
    cb = DeepCacheCFGCutoffCallback(guidance_end, halves, helper)
    return dict(callback_on_step_end=cb, callback_on_step_end_tensor_inputs=cb.tensor_inputs)
