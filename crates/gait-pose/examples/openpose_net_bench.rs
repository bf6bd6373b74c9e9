//! Per-frame time of the COCO-18 OpenPose network on candle, one 368x368
//! input, synthetic weights (tools/openpose/synthetic_weights.py).
//! Driven by tools/openpose/bench_net.py, which times torch in the same run.
//!
//!     cargo run --release -p gait-pose --example openpose_net_bench -- ROUNDS

#[path = "../tests/openpose_net/synthetic.rs"]
mod synthetic;

use std::collections::HashMap;
use std::time::Instant;

use candle_core::{Device, Tensor};
use gait_pose::openpose::net;
use gait_pose::openpose::{NetInput, OpenposeNet};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rounds: usize = std::env::args().nth(1).map_or(Ok(3), |a| a.parse())?;
    let mut tensors = HashMap::new();
    for (k, (name, shape)) in net::coco18_layout().into_iter().enumerate() {
        // The torch name only decides the scale; the checkpoint name ends the same way.
        let n = shape.iter().product();
        let v = synthetic::values(k, n, synthetic::scale(&name, &shape));
        tensors.insert(name, Tensor::from_vec(v, shape, &Device::Cpu)?);
    }
    let mut model = net::candle_from_tensors(tensors)?;
    let (h, w) = (368, 368);
    // Same pattern as bench_net.py.
    let data = (0..3 * h * w)
        .map(|i| ((i * 7919) % 256) as f32 / 256.0 - 0.5)
        .collect();
    let input = NetInput {
        data,
        height: h,
        width: w,
    };
    model.run(&input)?; // warm-up
    let t = Instant::now();
    for _ in 0..rounds {
        model.run(&input)?;
    }
    println!(
        "candle_ms {:.1}",
        t.elapsed().as_secs_f64() * 1000.0 / rounds as f64
    );
    Ok(())
}
