//! Per-frame time of the BlazePose estimator (static mode: detector + landmark
//! model on every frame), for tools/blazepose/bench.py.
//! Usage: blazepose_bench MODELS_DIR candle|ort ROUNDS IMAGE...

use std::time::Instant;

use gait_core::{Backend, Frame, StageContext};
use gait_pose::blazepose::{BlazeposeConfig, PersonChoice};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 5 {
        return Err("usage: blazepose_bench MODELS_DIR candle|ort ROUNDS IMAGE...".into());
    }
    let backend = match args[2].as_str() {
        "ort" => Backend::Ort,
        _ => Backend::Candle,
    };
    let rounds: usize = args[3].parse()?;
    let frames = args[4..]
        .iter()
        .enumerate()
        .map(|(i, p)| Ok(Frame::new(i, image::open(p)?.to_rgb8())))
        .collect::<Result<Vec<_>, image::ImageError>>()?;
    let config = BlazeposeConfig {
        backend,
        person: PersonChoice::Rule(gait_pose::PersonRule::MostConfident),
        tracking: false,
        ..Default::default()
    };
    let mut est = config.build(&StageContext::new(&args[1]))?;
    est.estimate(&frames[..1])?; // warm-up
    let start = Instant::now();
    for _ in 0..rounds {
        for f in &frames {
            est.estimate(std::slice::from_ref(f))?;
        }
    }
    let ms = start.elapsed().as_secs_f64() * 1000.0 / (rounds * frames.len()) as f64;
    println!("{ms:.3}");
    Ok(())
}
