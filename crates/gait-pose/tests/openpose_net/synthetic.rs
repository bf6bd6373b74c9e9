//! The synthetic OpenPose weights of tools/openpose/synthetic_weights.py, bit for bit:
//! for tensor `k` (manifest order) and element `i`,
//! `u = splitmix64(SEED ^ (k << 32) ^ i)`, `v = (u >> 40) as f32 / 2^24`,
//! `value = (2v - 1) * scale` in f32, with scale `f32(sqrt(6 / fan_in))` for conv
//! weights, 0.01 for biases and 0.25 for PReLU slopes.

pub const SEED: u64 = 0x6A1D_2026_0E1F_0001;

fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The formula's scale for a tensor of this torch name and shape.
pub fn scale(name: &str, shape: &[usize]) -> f32 {
    if name.ends_with(".weight") && shape.len() == 4 {
        let fan_in = (shape[1] * shape[2] * shape[3]) as f64;
        (6.0 / fan_in).sqrt() as f32
    } else if name.ends_with(".bias") {
        0.01
    } else if shape.len() == 1 {
        0.25
    } else {
        panic!("no synthetic scale for {name} {shape:?}")
    }
}

/// `n` values of tensor `k` with scale `scale`.
pub fn values(k: usize, n: usize, scale: f32) -> Vec<f32> {
    (0..n as u64)
        .map(|i| {
            let u = splitmix64(SEED ^ ((k as u64) << 32) ^ i);
            let v = (u >> 40) as f32 / 16_777_216.0;
            (2.0 * v - 1.0) * scale
        })
        .collect()
}
