"""Deterministic synthetic weights for the OpenPose networks (no real weights can be downloaded here).

The same formula is implemented in Rust (crates/gait-pose/tests/openpose_net.rs, `synthetic`), so full-size
networks (~52M parameters) can be checked without committing their weights. For the tensor with index k in a
manifest's order (the torch model's state_dict order) and its element i (row-major):

    u      = splitmix64(SEED ^ (k << 32) ^ i)                  (uint64, wrapping)
    v      = f32(u >> 40) / 2^24                                 (exact: a 24-bit integer, then a power of two)
    value  = f32(2 v - 1) * scale                                (one f32 rounding, IEEE round-to-nearest)

with scale = f32(sqrt(6 / fan_in)) (computed in f64, then cast) for conv weights, fan_in = in_ch * kh * kw
(He-uniform: activations keep their size through the ~90 conv layers), f32(0.01) for biases and f32(0.25)
for PReLU slopes (BODY_25).
"""
import numpy as np

SEED = 0x6A1D_2026_0E1F_0001
M64 = np.uint64(0xFFFFFFFFFFFFFFFF)


def splitmix64(x: np.ndarray) -> np.ndarray:
    with np.errstate(over="ignore"):
        z = x + np.uint64(0x9E3779B97F4A7C15)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        return z ^ (z >> np.uint64(31))


def scale_for(name: str, shape) -> np.float32:
    if name.endswith(".weight") and len(shape) == 4:
        fan_in = shape[1] * shape[2] * shape[3]
        return np.float32(np.sqrt(6.0 / fan_in))
    if name.endswith(".bias"):
        return np.float32(0.01)
    if len(shape) == 1:  # PReLU slope (`...weight` of an nn.PReLU)
        return np.float32(0.25)
    raise ValueError(f"no synthetic scale for {name} {shape}")


def tensor(k: int, name: str, shape) -> np.ndarray:
    n = int(np.prod(shape))
    i = np.arange(n, dtype=np.uint64)
    u = splitmix64(np.uint64(SEED) ^ (np.uint64(k) << np.uint64(32)) ^ i)
    v = (u >> np.uint64(40)).astype(np.float32) / np.float32(2**24)
    w = (np.float32(2) * v - np.float32(1)) * scale_for(name, shape)
    return w.astype(np.float32).reshape(shape)


def state_dict(manifest):
    """{name: array} for a manifest [(name, shape)], names as in the manifest."""
    return {name: tensor(k, name, shape) for k, (name, shape) in enumerate(manifest)}
